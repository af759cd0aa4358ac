"""The web application of the 2AFC experiment (Starlette; served by uvicorn).

- :func:`create_app` — the ASGI application for a :class:`~nmmm.experiment.pairs.PairSet`
  and a response database.
- :func:`serve` — run it with uvicorn (what ``nmmm experiment serve`` calls).

Participant routes (JSON; the page itself is ``static/index.html`` + ``app.js``):

==========================================================  ========================================
``GET  /api/config``                                        question, consent, calibration, timing
``POST /api/participants``                                  ``{participant_id, consent: true,
                                                            client_token}`` -> session
``GET  /api/session/{token}``                               progress of the session
``GET  /api/session/{token}/trial``                         the next unanswered trial
``GET  /api/session/{token}/stimuli/{trial}``               every view of a trial, one raw body
``GET  /api/session/{token}/image/{trial}/{slot}[/{eye}]``  one view, uncompressed BMP
``POST /api/session/{token}/responses``                     ``{response_id, trial_index, choice,
                                                            rt_ms}``
==========================================================  ========================================

Experimenter routes need the admin token (``Authorization: Bearer <token>`` or
``?token=<token>``): ``GET /admin`` (participants, progress, resume links),
``GET /admin/export.csv``, ``GET /admin/participants.json``.

What the participant sees: consent text and calibration note, then for each trial a neutral
blank interval (``blank_ms``) and both stimuli at once, in identical neutral frames, at one
image pixel per device pixel; the response time runs from the first frame showing them to the
click or key press (ArrowLeft/ArrowRight, or ArrowUp/ArrowDown in stereo mode).

What a participant can observe, with the browser's developer tools or any HTTP client
------------------------------------------------------------------------------------------
*Only the pixels differ.* The page gets all views of a trial in **one** response
(``/stimuli/{trial}``, ``application/octet-stream``): the raw 8-bit sRGB bytes of slot 0 then
slot 1 (stereo: the left-eye then the right-eye view of the top pair, then of the bottom pair),
rows top to bottom, ``3 × width × height`` bytes per view, drawn into canvases by the page.
Both images are prepared (decoded, converted to sRGB, resampled to one size) at server start
and held in memory, so:

- the length of the body is ``n_views × 3 × width × height`` whichever slot holds the
  photograph: no compression, no encoder parameters, no metadata;
- its headers are the same for every trial of a session (``content-type``,
  ``content-length``, ``cache-control: no-store`` and fixed security headers; uvicorn adds
  ``date`` and ``server``) — no ``ETag``, no ``Last-Modified``, nothing derived from a file;
- there is no order or timing between the two images to watch: they arrive together, and
  the work of the server (one database read, one copy of bytes in memory) does not depend on
  which image is where.

The per-view route (``/image/...``, an uncompressed 24-bit BMP whose 54-byte header follows
from the pixel size alone) obeys the same rules, for tools that want one image per request.
The JSON never says which slot holds the photograph, nor gives pair ids, labels or file names;
image URLs name the trial and the screen slot only; the acknowledgement of a response does
not say whether it was correct. A participant *can* see: their own progress, the pixel size of
the stimuli (the same for both images of a trial), the number of trials, and the pixels.

Robustness: malformed input is a 4xx with a message, never a 500 — integers beyond 18 digits,
non-finite numbers (``NaN``, ``Infinity``, ``1e999``), JSON nested more than
:data:`MAX_JSON_DEPTH` deep, out-of-range trial indices. A database that cannot store (disk
full, read-only) is a 503 with a message and ``Retry-After``; nothing is acknowledged that was
not committed. A participant whose creation reply was lost re-sends the same id with the same
``client_token`` and resumes. The server accepts no file uploads: JSON bodies are limited to
16 KiB, anything else (multipart uploads included) is refused with 413 / 415, and a JSON body
with a field the route does not accept is refused with 422 naming the field.
"""

from __future__ import annotations

import hashlib
import html
import json
import logging
import math
import re
import secrets
import uuid
from contextlib import asynccontextmanager
from pathlib import Path

from nmmm.errors import DataFileError, InvalidInputError, NmmmError
from nmmm.experiment.storage import (
    DuplicateSubmissionError,
    ParticipantExistsError,
    ResponseStore,
    StorageUnavailableError,
    TrialOrderError,
    UnknownParticipantError,
)

STATIC_DIR = Path(__file__).parent / "static"
MAX_BODY_BYTES = 16 * 1024
#: Deepest nesting of JSON objects/arrays accepted in a request body (the API needs 2).
MAX_JSON_DEPTH = 4
#: Longest integer literal accepted in a request body (digits); every integer of the API is smaller.
MAX_INT_DIGITS = 18
#: Seconds a client is asked to wait (``Retry-After``) when the database cannot store.
RETRY_AFTER_S = 2
_log = logging.getLogger("nmmm.experiment")
_PARTICIPANT_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
_CLIENT_TOKEN_RE = re.compile(r"^[A-Za-z0-9_-]{16,128}$")
_TRIAL_RE = re.compile(r"^[0-9]{1,9}$")
_SLOTS = {False: ("left", "right"), True: ("top", "bottom")}
_SECURITY_HEADERS = {
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "X-Frame-Options": "DENY",
    "Content-Security-Policy": "default-src 'self'; img-src 'self'; style-src 'self'; script-src 'self'; "
                               "connect-src 'self'; frame-ancestors 'none'",
}


class HTTPProblem(Exception):
    """An error answered as ``{"error": message}`` with an HTTP status."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status
        self.message = message


def _short(x, n: int = 40) -> str:
    """``repr`` of a client value, cut to ``n`` characters (a 4000-digit integer stays readable)."""
    text = repr(x)
    return text if len(text) <= n else text[: n - 3] + "..."


def _json_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise HTTPProblem(400, f"integer {text[:20]}... with {len(text.lstrip('-'))} digits is out of range; "
                               f"integers in this API have at most {MAX_INT_DIGITS} digits")
    return int(text)


def _json_float(text: str) -> float:
    x = float(text)
    if not math.isfinite(x):
        raise HTTPProblem(400, f"number {text[:40]} is out of the range of a double; send a finite number")
    return x


def _json_constant(name: str):
    raise HTTPProblem(400, f"{name} is not a number JSON allows; send a finite number")


def _json_depth(x) -> int:
    depth, stack = 0, [(x, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, (dict, list)):
            depth = max(depth, d)
            stack.extend((c, d + 1) for c in (v.values() if isinstance(v, dict) else v))
    return depth


def parse_json_body(body: bytes):
    """Decode a request body as strict JSON, or raise :class:`HTTPProblem` (400) saying why.

    Refused: invalid UTF-8 or JSON, ``NaN`` / ``Infinity`` and numbers that overflow a double,
    integer literals longer than :data:`MAX_INT_DIGITS` digits, nesting deeper than
    :data:`MAX_JSON_DEPTH`.
    """
    try:
        data = json.loads(body.decode("utf-8"), parse_int=_json_int, parse_float=_json_float,
                          parse_constant=_json_constant)
    except RecursionError:
        raise HTTPProblem(400, f"request body is nested too deeply; at most {MAX_JSON_DEPTH} levels of "
                               f"objects and arrays are accepted") from None
    except UnicodeDecodeError as exc:
        raise HTTPProblem(400, f"request body is not UTF-8 text: {exc}") from None
    except ValueError as exc:   # JSONDecodeError, and int() of a literal beyond Python's digit limit
        raise HTTPProblem(400, f"request body is not valid JSON: {exc}") from None
    if _json_depth(data) > MAX_JSON_DEPTH:
        raise HTTPProblem(400, f"request body is nested too deeply; at most {MAX_JSON_DEPTH} levels of objects "
                               f"and arrays are accepted")
    return data


def create_app(pairset, db_path, *, admin_token: str | None = None, cache_dir=None,
               progress: bool = False):
    """Build the ASGI application.

    Parameters
    ----------
    pairset : PairSet
        From :func:`nmmm.experiment.pairs.load_pairs`.
    db_path : path
        The SQLite response database (created if absent; WAL mode).
    admin_token : str, optional
        Token of the experimenter routes; a random one is drawn if None (``app.state.admin_token``).
    cache_dir : path or False, optional
        The content-addressed cache of prepared stimuli, reused by a restarted server
        (:func:`nmmm.experiment.stimuli.default_cache_dir` if None; ``False``: none, prepare
        every image at every start). The prepared stimuli are served from memory.
    """
    from starlette.applications import Starlette
    from starlette.concurrency import run_in_threadpool
    from starlette.requests import Request
    from starlette.responses import FileResponse, HTMLResponse, JSONResponse, Response
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    from nmmm.experiment.export import write_csv
    from nmmm.experiment.stimuli import StimulusStore, default_cache_dir

    store = ResponseStore(db_path)
    try:
        store.register_pairs(pairset)
        if cache_dir is None:
            try:
                stimuli = StimulusStore(pairset, default_cache_dir(), progress=progress)
            except DataFileError:   # no writable default cache: prepare in memory only
                stimuli = StimulusStore(pairset, None, progress=progress)
        else:
            stimuli = StimulusStore(pairset, cache_dir or None, progress=progress)
    except BaseException:
        store.close()
        raise
    settings = pairset.settings
    stereo = settings.stereo
    slots = _SLOTS[stereo]
    admin_token = admin_token or secrets.token_urlsafe(18)
    consent_sha = hashlib.sha256(settings.consent_text.encode()).hexdigest()

    n_trials = pairset.n_trials

    def problem(status, message, headers=None):
        return JSONResponse({"error": message}, status_code=status,
                            headers={"Cache-Control": "no-store", **(headers or {})})

    def ok(payload, status=200):
        return JSONResponse(payload, status_code=status, headers={"Cache-Control": "no-store"})

    async def read_json(request: Request, accepted: tuple) -> dict:
        """The JSON object of a request; keys outside ``accepted`` are refused (422), so a
        misspelt field (``rt`` for ``rt_ms``) is not silently dropped."""
        ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
        length = request.headers.get("content-length")
        if length is not None and length.isdigit() and int(length) > MAX_BODY_BYTES:
            raise HTTPProblem(413, f"request body of {int(length)} bytes is too large; at most "
                                   f"{MAX_BODY_BYTES} bytes of JSON are accepted (this server takes no uploads)")
        if ctype != "application/json":
            raise HTTPProblem(415, f"content type {ctype or 'none'!r} is not accepted; send application/json "
                                   f"(this server accepts no file uploads)")
        body = bytearray()
        async for chunk in request.stream():
            body += chunk
            if len(body) > MAX_BODY_BYTES:
                raise HTTPProblem(413, f"request body is too large; at most {MAX_BODY_BYTES} bytes of JSON "
                                       f"are accepted (this server takes no uploads)")
        data = parse_json_body(bytes(body))
        if not isinstance(data, dict):
            raise HTTPProblem(400, "request body must be a JSON object")
        extra = sorted(set(data) - set(accepted))
        if extra:
            raise HTTPProblem(422, f"unknown field(s) {extra} in the request body; this route accepts only "
                                   f"{list(accepted)}")
        return data

    async def session_of(request: Request) -> dict:
        token = request.path_params["token"]
        try:
            return await run_in_threadpool(store.participant_by_token, token)
        except UnknownParticipantError as exc:
            raise HTTPProblem(404, str(exc)) from None

    def trial_of(request: Request) -> int:
        text = request.path_params["trial"]
        if not _TRIAL_RE.match(text) or int(text) >= n_trials:
            raise HTTPProblem(404, f"no trial {_short(text)}: the trials of a session are numbered 0 to "
                                   f"{n_trials - 1}")
        return int(text)

    def progress_payload(part, answered):
        return {"participant_id": part["participant_id"], "n_trials": part["n_trials"],
                "answered": answered, "done": answered >= part["n_trials"]}

    # -- participant routes -----------------------------------------------------------
    async def index(request):
        return FileResponse(STATIC_DIR / "index.html", media_type="text/html", headers={"Cache-Control": "no-store"})

    async def healthz(request):
        return ok({"ok": True})

    async def config(request):
        return ok({
            "title": settings.title, "question": settings.question,
            "consent_text": settings.consent_text, "consent_sha256": consent_sha,
            "calibration_note": settings.calibration_text(),
            "viewing_distance_cm": settings.viewing_distance_cm, "blank_ms": settings.blank_ms,
            "stereo": stereo, "stereo_arrangement": settings.stereo_arrangement,
            "background": settings.background, "frame_px": settings.frame_px,
            "n_trials": pairset.n_trials, "slots": list(slots),
        })

    async def create_participant(request):
        data = await read_json(request, ("participant_id", "consent", "screen", "client_token"))
        pid = data.get("participant_id")
        if not isinstance(pid, str) or not _PARTICIPANT_RE.match(pid.strip()):
            raise HTTPProblem(400, "participant_id must be 1-64 characters: letters, digits, '.', '_' or '-'")
        if data.get("consent") is not True:
            raise HTTPProblem(400, "consent is required: the participant must tick the consent box "
                                   "(send \"consent\": true)")
        client_token = data.get("client_token")
        if client_token is not None and not (isinstance(client_token, str) and _CLIENT_TOKEN_RE.match(client_token)):
            raise HTTPProblem(400, "client_token must be 16-128 characters from letters, digits, '_' and '-' "
                                   "(a random token the page keeps, to resume if the reply is lost)")
        screen = data.get("screen") if isinstance(data.get("screen"), dict) else {}
        try:
            part = await run_in_threadpool(
                lambda: store.create_participant(pid.strip(), pairset, consent_sha256=consent_sha,
                                                 user_agent=request.headers.get("user-agent"), screen=screen,
                                                 client_token=client_token))
        except ParticipantExistsError as exc:
            raise HTTPProblem(409, str(exc)) from None
        answered = await run_in_threadpool(store.answered_count, part["participant_id"]) if part["resumed"] else 0
        return ok({"session": part["session_token"], "resumed": part["resumed"], **progress_payload(part, answered)},
                  status=200 if part["resumed"] else 201)

    async def session_info(request):
        part = await session_of(request)
        answered = await run_in_threadpool(store.answered_count, part["participant_id"])
        return ok(progress_payload(part, answered))

    async def next_trial(request):
        part = await session_of(request)
        pid = part["participant_id"]
        trial = await run_in_threadpool(store.next_trial, pid)
        answered = await run_in_threadpool(store.answered_count, pid)
        payload = progress_payload(part, answered)
        if trial is None:
            return ok(payload)
        session_base = f"/api/session/{part['session_token']}"
        base = f"{session_base}/image/{trial['trial_index']}"
        width, height = stimuli.size(trial["pair_id"])
        if stereo:
            images = {slot: {"left_eye": f"{base}/{slot}/left", "right_eye": f"{base}/{slot}/right"}
                      for slot in slots}
            order = [[slot, eye] for slot in slots for eye in ("left_eye", "right_eye")]
        else:
            images = {slot: f"{base}/{slot}" for slot in slots}
            order = [[slot, None] for slot in slots]
        payload.update({"trial_index": trial["trial_index"], "images": images, "width": width, "height": height,
                        "stimuli": {"url": f"{session_base}/stimuli/{trial['trial_index']}", "encoding": "rgb8",
                                    "views": order, "bytes": len(order) * 3 * width * height}})
        return ok(payload)

    async def trial_record(request):
        part = await session_of(request)
        index = trial_of(request)
        try:
            return await run_in_threadpool(store.trial, part["participant_id"], index)
        except InvalidInputError as exc:
            raise HTTPProblem(404, str(exc)) from None

    stimulus_headers = {"Cache-Control": "no-store"}

    async def trial_stimuli(request):
        trial = await trial_record(request)
        return Response(stimuli.trial_body(trial["pair_id"], trial["photo_slot"]),
                        media_type="application/octet-stream", headers=stimulus_headers)

    async def image(request):
        slot_name = request.path_params["slot"]
        eye = request.path_params.get("eye")
        if slot_name not in slots:
            raise HTTPProblem(404, f"unknown slot {_short(slot_name)}; expected one of {list(slots)}")
        if stereo != (eye is not None) or eye not in (None, "left", "right"):
            raise HTTPProblem(404, "stereo images need /left or /right; mono images take no eye")
        trial = await trial_record(request)
        slot = slots.index(slot_name)
        role = "photo" if slot == trial["photo_slot"] else "rendered"
        return Response(stimuli.bmp(trial["pair_id"], role, eye), media_type="image/bmp", headers=stimulus_headers)

    async def respond(request):
        part = await session_of(request)
        data = await read_json(request, ("response_id", "trial_index", "choice", "rt_ms"))
        rid = data.get("response_id")
        try:
            rid = str(uuid.UUID(str(rid)))
        except (ValueError, TypeError, AttributeError):
            raise HTTPProblem(400, "response_id must be a UUID generated by the client for this response") from None
        tidx = data.get("trial_index")
        if not isinstance(tidx, int) or isinstance(tidx, bool) or tidx < 0:
            raise HTTPProblem(400, f"trial_index must be a non-negative integer, got {_short(tidx)}")
        if tidx >= n_trials:
            raise HTTPProblem(409, f"there is no trial {tidx} for this participant (trials 0 to {n_trials - 1})")
        choice = data.get("choice")
        if not isinstance(choice, str) or choice not in slots:
            raise HTTPProblem(400, f"choice must be one of {list(slots)}, got {_short(choice)}")
        rt = data.get("rt_ms")
        if isinstance(rt, bool) or not isinstance(rt, (int, float)):
            raise HTTPProblem(400, f"rt_ms must be a number of milliseconds, got {_short(rt)}")
        if not 0 <= rt <= 3_600_000:
            raise HTTPProblem(400, f"rt_ms must be a finite number of milliseconds in [0, 3600000], got {_short(rt)}")
        pid = part["participant_id"]
        try:
            result = await run_in_threadpool(store.record_response, pid, tidx, rid, slots.index(choice), float(rt))
        except (DuplicateSubmissionError, TrialOrderError) as exc:
            raise HTTPProblem(409, str(exc)) from None
        except InvalidInputError as exc:
            raise HTTPProblem(400, str(exc)) from None
        answered = await run_in_threadpool(store.answered_count, pid)
        payload = {"status": result["status"], "trial_index": tidx, "response_id": rid,
                   **progress_payload(part, answered)}
        return ok(payload, status=201 if result["status"] == "stored" else 200)

    # -- experimenter routes ----------------------------------------------------------
    def check_admin(request):
        auth = request.headers.get("authorization", "")
        given = auth[7:].strip() if auth.lower().startswith("bearer ") else request.query_params.get("token", "")
        if not given:
            raise HTTPProblem(401, "admin token required (Authorization: Bearer <token> or ?token=<token>)")
        if not secrets.compare_digest(given.encode(), admin_token.encode()):
            raise HTTPProblem(403, "wrong admin token")

    async def admin_export(request):
        check_admin(request)

        def build():
            import io
            buf = io.StringIO()
            write_csv(store.db_path, buf)
            return buf.getvalue()

        text = await run_in_threadpool(build)
        return Response(text, media_type="text/csv; charset=utf-8",
                        headers={"Content-Disposition": 'attachment; filename="responses.csv"',
                                 "Cache-Control": "no-store"})

    async def admin_participants(request):
        check_admin(request)
        rows = await run_in_threadpool(store.participants)
        return ok({"participants": rows})

    async def admin_page(request):
        check_admin(request)
        rows = await run_in_threadpool(store.participants)
        tok = html.escape(request.query_params.get("token", ""), quote=True)
        body = "".join(
            f"<tr><td>{html.escape(r['participant_id'])}</td><td>{r['answered']} / {r['n_trials']}</td>"
            f"<td>{html.escape(r['created_at'])}</td>"
            f"<td><a href=\"/?session={html.escape(r['session_token'], quote=True)}\">resume link</a></td></tr>"
            for r in rows)
        page = (f"<!doctype html><meta charset=utf-8><title>Experimenter: {html.escape(settings.title)}</title>"
                f"<h1>Experimenter page</h1><p>{len(rows)} participant(s). "
                f"<a href=\"/admin/export.csv?token={tok}\">Export responses (CSV)</a></p>"
                f"<table><tr><th>participant</th><th>answered</th><th>started (UTC)</th><th></th></tr>{body}</table>")
        return HTMLResponse(page, headers={"Cache-Control": "no-store"})

    def wrap(fn):
        async def endpoint(request):
            try:
                response = await fn(request)
            except HTTPProblem as exc:
                response = problem(exc.status, exc.message)
            except StorageUnavailableError as exc:
                response = problem(503, str(exc), {"Retry-After": str(RETRY_AFTER_S)})
            except NmmmError as exc:
                response = problem(400, str(exc))
            except Exception as exc:   # a bug: say so in JSON (uvicorn would answer plain text)
                _log.exception("internal error on %s %s", request.method, request.url.path)
                response = problem(500, f"internal error ({type(exc).__name__}); nothing was stored by this "
                                        f"request; please report it to the experimenter")
            response.headers.update(_SECURITY_HEADERS)
            return response
        return endpoint

    routes = [
        Route("/", wrap(index)),
        Route("/healthz", wrap(healthz)),
        Route("/api/config", wrap(config)),
        Route("/api/participants", wrap(create_participant), methods=["POST"]),
        Route("/api/session/{token}", wrap(session_info)),
        Route("/api/session/{token}/trial", wrap(next_trial)),
        Route("/api/session/{token}/stimuli/{trial}", wrap(trial_stimuli)),
        Route("/api/session/{token}/image/{trial}/{slot}", wrap(image)),
        Route("/api/session/{token}/image/{trial}/{slot}/{eye}", wrap(image)),
        Route("/api/session/{token}/responses", wrap(respond), methods=["POST"]),
        Route("/admin", wrap(admin_page)),
        Route("/admin/export.csv", wrap(admin_export)),
        Route("/admin/participants.json", wrap(admin_participants)),
        Mount("/static", app=StaticFiles(directory=STATIC_DIR), name="static"),
    ]

    @asynccontextmanager
    async def lifespan(app):
        try:
            yield
        finally:
            store.close()

    async def not_found(request, exc):
        status = getattr(exc, "status_code", 404)
        msg = {404: f"no such page: {request.url.path}", 405: f"method {request.method} not allowed here"}
        return JSONResponse({"error": msg.get(status, getattr(exc, "detail", "error"))}, status_code=status,
                            headers=_SECURITY_HEADERS)

    app = Starlette(routes=routes, lifespan=lifespan, exception_handlers={404: not_found, 405: not_found})
    app.state.admin_token = admin_token
    app.state.store = store
    app.state.pairset = pairset
    app.state.stimuli = stimuli
    return app


def serve(pairs_toml, db_path, *, host: str = "127.0.0.1", port: int = 8000, admin_token: str | None = None,
          log_level: str = "warning", echo=print, cache_dir=None):
    """Load ``pairs_toml``, prepare the stimuli, and serve the experiment with uvicorn (blocking).

    Prepared stimuli are cached on disk by content (``cache_dir``, default
    :func:`nmmm.experiment.stimuli.default_cache_dir`): a restart after a crash reads them back
    instead of preparing them again, so participants wait for the restart only.
    """
    import uvicorn

    from nmmm.experiment.pairs import load_pairs

    pairset = load_pairs(pairs_toml)
    app = create_app(pairset, db_path, admin_token=admin_token, progress=True, cache_dir=cache_dir)
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    c = app.state.stimuli.counts
    echo(f"nmmm experiment: {len(pairset)} pair(s), {pairset.n_trials} trial(s) per participant, "
         f"responses in {db_path}; stimuli: {c['prepared']} prepared, {c['reused']} reused from "
         f"{app.state.stimuli.cache_dir or 'no cache'}")
    echo(f"participants: http://{shown}:{port}/")
    echo(f"experimenter: http://{shown}:{port}/admin?token={app.state.admin_token}")
    uvicorn.run(app, host=host, port=port, log_level=log_level, access_log=False)


__all__ = ["create_app", "serve", "parse_json_body", "MAX_BODY_BYTES", "MAX_JSON_DEPTH", "MAX_INT_DIGITS"]
