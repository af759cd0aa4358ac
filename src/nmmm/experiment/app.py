"""The web application of the 2AFC experiment (Starlette; served by uvicorn).

- :func:`create_app` — the ASGI application for a :class:`~nmmm.experiment.pairs.PairSet`
  and a response database.
- :func:`serve` — run it with uvicorn (what ``nmmm experiment serve`` calls).

Participant routes (JSON; the page itself is ``static/index.html`` + ``app.js``):

=======================================================  ==========================================
``GET  /api/config``                                     question, consent, calibration note, timing
``POST /api/participants``                               ``{participant_id, consent: true}`` -> session
``GET  /api/session/{token}``                            progress of the session
``GET  /api/session/{token}/trial``                      the next unanswered trial (image URLs)
``GET  /api/session/{token}/image/{trial}/{slot}[/{eye}]`` one prepared stimulus (PNG)
``POST /api/session/{token}/responses``                  ``{response_id, trial_index, choice, rt_ms}``
=======================================================  ==========================================

Experimenter routes need the admin token (``Authorization: Bearer <token>`` or
``?token=<token>``): ``GET /admin`` (participants, progress, resume links),
``GET /admin/export.csv``, ``GET /admin/participants.json``.

What the participant sees: consent text and calibration note, then for each trial a neutral
blank interval (``blank_ms``) and both stimuli at once, in identical neutral frames, at one
image pixel per device pixel; the response time runs from the first frame showing them to the
click or key press (ArrowLeft/ArrowRight, or ArrowUp/ArrowDown in stereo mode).

What a participant can learn: their own progress, nothing else. Image URLs name the trial
and the screen slot only; the JSON never says which slot holds the photograph, nor gives pair
ids, labels or file names, and the acknowledgement of a response does not say whether it was
correct. The server accepts no file uploads: JSON bodies are limited to 16 KiB, anything else
(multipart uploads included) is refused with 413 / 415, and a JSON body with a field the
route does not accept (``{"participant_id", "consent", "screen"}`` for participants, the four
fields above for responses) is refused with 422 naming the field.
"""

from __future__ import annotations

import hashlib
import html
import json
import re
import secrets
import shutil
import tempfile
import uuid
from contextlib import asynccontextmanager
from pathlib import Path

from nmmm.errors import InvalidInputError, NmmmError
from nmmm.experiment.storage import (
    DuplicateSubmissionError,
    ParticipantExistsError,
    ResponseStore,
    TrialOrderError,
    UnknownParticipantError,
)

STATIC_DIR = Path(__file__).parent / "static"
MAX_BODY_BYTES = 16 * 1024
_PARTICIPANT_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
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
    cache_dir : path, optional
        Where the prepared stimuli are written (a temporary directory by default).
    """
    from starlette.applications import Starlette
    from starlette.concurrency import run_in_threadpool
    from starlette.requests import Request
    from starlette.responses import FileResponse, HTMLResponse, JSONResponse, Response
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    from nmmm.experiment.export import write_csv
    from nmmm.experiment.stimuli import StimulusStore

    store = ResponseStore(db_path)
    tmp = None
    try:
        store.register_pairs(pairset)
        if cache_dir is None:
            tmp = tempfile.TemporaryDirectory(prefix="nmmm-stimuli-")
            cache_dir = tmp.name
        stimuli = StimulusStore(pairset, cache_dir, progress=progress)
    except BaseException:
        store.close()
        if tmp is not None:
            tmp.cleanup()
        raise
    settings = pairset.settings
    stereo = settings.stereo
    slots = _SLOTS[stereo]
    admin_token = admin_token or secrets.token_urlsafe(18)
    consent_sha = hashlib.sha256(settings.consent_text.encode()).hexdigest()

    def problem(status, message):
        return JSONResponse({"error": message}, status_code=status, headers={"Cache-Control": "no-store"})

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
        try:
            data = json.loads(body.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise HTTPProblem(400, f"request body is not valid JSON: {exc}") from None
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
        data = await read_json(request, ("participant_id", "consent", "screen"))
        pid = data.get("participant_id")
        if not isinstance(pid, str) or not _PARTICIPANT_RE.match(pid.strip()):
            raise HTTPProblem(400, "participant_id must be 1-64 characters: letters, digits, '.', '_' or '-'")
        if data.get("consent") is not True:
            raise HTTPProblem(400, "consent is required: the participant must tick the consent box "
                                   "(send \"consent\": true)")
        screen = data.get("screen") if isinstance(data.get("screen"), dict) else {}
        try:
            part = await run_in_threadpool(
                lambda: store.create_participant(pid.strip(), pairset, consent_sha256=consent_sha,
                                                 user_agent=request.headers.get("user-agent"), screen=screen))
        except ParticipantExistsError as exc:
            raise HTTPProblem(409, str(exc)) from None
        return ok({"session": part["session_token"], **progress_payload(part, 0)}, status=201)

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
        base = f"/api/session/{part['session_token']}/image/{trial['trial_index']}"
        width, height = stimuli.size(trial["pair_id"], "left" if stereo else None)
        if stereo:
            images = {slot: {"left_eye": f"{base}/{slot}/left", "right_eye": f"{base}/{slot}/right"}
                      for slot in slots}
        else:
            images = {slot: f"{base}/{slot}" for slot in slots}
        payload.update({"trial_index": trial["trial_index"], "images": images,
                        "width": width, "height": height})
        return ok(payload)

    async def image(request):
        part = await session_of(request)
        slot_name = request.path_params["slot"]
        eye = request.path_params.get("eye")
        if slot_name not in slots:
            raise HTTPProblem(404, f"unknown slot {slot_name!r}; expected one of {list(slots)}")
        if stereo != (eye is not None) or eye not in (None, "left", "right"):
            raise HTTPProblem(404, "stereo images need /left or /right; mono images take no eye")
        try:
            trial = await run_in_threadpool(store.trial, part["participant_id"], request.path_params["trial"])
        except InvalidInputError as exc:
            raise HTTPProblem(404, str(exc)) from None
        slot = slots.index(slot_name)
        role = "photo" if slot == trial["photo_slot"] else "rendered"
        return FileResponse(stimuli.path(trial["pair_id"], role, eye), media_type="image/png",
                            headers={"Cache-Control": "private, max-age=3600"})

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
            raise HTTPProblem(400, f"trial_index must be a non-negative integer, got {tidx!r}")
        choice = data.get("choice")
        if choice not in slots:
            raise HTTPProblem(400, f"choice must be one of {list(slots)}, got {choice!r}")
        rt = data.get("rt_ms")
        if isinstance(rt, bool) or not isinstance(rt, (int, float)):
            raise HTTPProblem(400, f"rt_ms must be a number of milliseconds, got {rt!r}")
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
            except NmmmError as exc:
                response = problem(400, str(exc))
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
        Route("/api/session/{token}/image/{trial:int}/{slot}", wrap(image)),
        Route("/api/session/{token}/image/{trial:int}/{slot}/{eye}", wrap(image)),
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
            if tmp is not None:
                tmp.cleanup()

    async def not_found(request, exc):
        status = getattr(exc, "status_code", 404)
        msg = {404: f"no such page: {request.url.path}", 405: f"method {request.method} not allowed here"}
        return JSONResponse({"error": msg.get(status, getattr(exc, "detail", "error"))}, status_code=status,
                            headers=_SECURITY_HEADERS)

    app = Starlette(routes=routes, lifespan=lifespan, exception_handlers={404: not_found, 405: not_found})
    app.state.admin_token = admin_token
    app.state.store = store
    app.state.pairset = pairset
    return app


def serve(pairs_toml, db_path, *, host: str = "127.0.0.1", port: int = 8000, admin_token: str | None = None,
          log_level: str = "warning", echo=print):
    """Load ``pairs_toml``, prepare the stimuli, and serve the experiment with uvicorn (blocking)."""
    import uvicorn

    from nmmm.experiment.pairs import load_pairs

    pairset = load_pairs(pairs_toml)
    # prepared stimuli live in one temporary folder per database, emptied at every start (a
    # killed server leaves it behind; the next start reuses the place)
    key = hashlib.sha256(str(Path(db_path).resolve()).encode()).hexdigest()[:16]
    cache_dir = Path(tempfile.gettempdir()) / f"nmmm-stimuli-{key}"
    shutil.rmtree(cache_dir, ignore_errors=True)
    app = create_app(pairset, db_path, admin_token=admin_token, progress=True, cache_dir=cache_dir)
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    echo(f"nmmm experiment: {len(pairset)} pair(s), {pairset.n_trials} trial(s) per participant, "
         f"responses in {db_path}")
    echo(f"participants: http://{shown}:{port}/")
    echo(f"experimenter: http://{shown}:{port}/admin?token={app.state.admin_token}")
    uvicorn.run(app, host=host, port=port, log_level=log_level, access_log=False)


__all__ = ["create_app", "serve", "MAX_BODY_BYTES"]
