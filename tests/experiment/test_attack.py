"""Attack the experiment as a participant with developer tools would (issue 20 items 1-2).

The pairs file is built so that the photographs compress very differently from the renders:
each 'photo' is a noisy camera-like JPEG (twice the resolution, EXIF and an ICC profile), each
'render' a smooth PNG gradient. Re-encoded to PNG the photograph would be several times
larger, which gave it away on every trial before (the positive control below shows that the
classifier used here finds it from that alone). Every trial is then fetched as a client would —
in-process over httpx (Starlette's TestClient), from a real uvicorn server on 127.0.0.1, and
by the participant page in chromium — and every observable is compared between the two
slots: status, headers, body length, completion order and time.

Classifier: for each observable feature, the difference left - right of a trial, turned into a
guess 'the photograph is on the left' by the best of the four sign rules (which sign, where
ties go) chosen on the even trials and scored on the odd ones. It must sit at chance: the
number right out of the ``n`` scored trials must not be significant in a two-sided exact
binomial test at alpha = 0.001 (e.g. between 34 and 66 of 100). A feature that is exactly equal
on every trial (lengths, headers) gives a constant guess, right on the trials whose
photograph happens to be on that side — half of them, by the counterbalanced placement.
"""

from __future__ import annotations

import concurrent.futures as cf
import io
import os
import sqlite3
import time
import uuid
import warnings

import numpy as np
import pytest
from experiment_helpers import CHROMIUM, CHROMIUM_ARGS
from PIL import Image, ImageCms

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

from nmmm.experiment.app import create_app
from nmmm.experiment.pairs import load_pairs, make_pairs_file
from nmmm.experiment.stats import binomial_test
from nmmm.experiment.stimuli import bmp_length, prepare_image

ALPHA = 0.001
N_PAIRS, REPS = 20, 2


def _attack_pairs(tmp, n_pairs=N_PAIRS, stereo=False, size=(64, 48)):
    """Noisy JPEG 'photographs' with EXIF + ICC at twice the size, smooth PNG 'renders'."""
    rng = np.random.default_rng(20)
    (tmp / "img").mkdir(parents=True, exist_ok=True)
    w, h = size
    y, x = np.mgrid[0:h, 0:w]
    srgb = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    exif = Image.Exif()
    exif[0x010F] = "CameraMaker"
    exif[0x0132] = "2024:01:01 12:00:00"

    def render(i, tag):
        base = np.array([90 + 5 * i, 100, 110])
        a = base + 20 * (x / w)[..., None] + 10 * (y / h)[..., None]
        p = tmp / "img" / f"render{i}{tag}.png"
        Image.fromarray(np.clip(a, 0, 255).astype(np.uint8)).save(p)
        return p

    def photo(i, tag):
        big = np.kron(np.array(Image.open(render(i, tag + "_src"))), np.ones((2, 2, 1)))
        a = big + rng.normal(0, 28, big.shape)            # sensor noise: compresses badly
        p = tmp / "img" / f"photo{i}{tag}.jpg"
        Image.fromarray(np.clip(a, 0, 255).astype(np.uint8)).save(p, quality=95, exif=exif.tobytes(),
                                                                   icc_profile=srgb)
        return p

    triples = [(render(i, ""), photo(i, ""), f"plate {i}") for i in range(n_pairs)]
    views = None
    if stereo:
        views = [((render(i, "L"), render(i, "R")), (photo(i, "L"), photo(i, "R"))) for i in range(n_pairs)]
    return make_pairs_file(triples, tmp / "pairs.toml", stereo_pairs=views, repetitions=REPS, blank_ms=0,
                           stereo=stereo)


@pytest.fixture(scope="module")
def attack_toml(tmp_path_factory):
    return _attack_pairs(tmp_path_factory.mktemp("attack"))


def _chance_bound(n):
    """Largest and smallest k (of n) not significant two-sided at ALPHA."""
    ks = [k for k in range(n + 1) if binomial_test(k, n, 0.5, "two-sided") >= ALPHA]
    return min(ks), max(ks)


def _classify(diffs, photo_left):
    """Best sign rule on the even trials, scored on the odd ones -> (k right, n scored)."""
    d = np.asarray(diffs, float)
    truth = np.asarray(photo_left, bool)
    rules = [lambda v: v > 0, lambda v: v >= 0, lambda v: v < 0, lambda v: v <= 0]
    train, test = np.arange(0, d.size, 2), np.arange(1, d.size, 2)
    best = max(rules, key=lambda r: np.sum(r(d[train]) == truth[train]))
    return int(np.sum(best(d[test]) == truth[test])), int(test.size)


def _assert_chance(features, photo_left, where):
    lo, hi = _chance_bound(len(photo_left) // 2)
    for name, diffs in features.items():
        k, n = _classify(diffs, photo_left)
        assert lo <= k <= hi, (f"{where}: the classifier on {name} picks the photograph on {k} of {n} trials "
                               f"(chance band {lo}-{hi} at alpha {ALPHA})")


def _photo_slots(db, pid):
    con = sqlite3.connect(db)
    try:
        return {t: s for t, s in con.execute("SELECT trial_index, photo_slot FROM trials WHERE participant_id=?",
                                             (pid,))}
    finally:
        con.close()


def _visible_headers(resp):
    # 'date' has one-second resolution and is the clock, not the image; everything else must match
    return sorted((k.lower(), v) for k, v in resp.headers.items() if k.lower() != "date")


def _session(c, pid):
    r = c.post("/api/participants", json={"participant_id": pid, "consent": True})
    assert r.status_code == 201, r.text
    return r.json()["session"]


def _fetch_trials(c, pid, slots=("left", "right"), eyes=(None,), concurrent=False):
    """Fetch every trial's per-slot images and the combined body as a client; answer it."""
    s = _session(c, pid)
    records = []
    pool = cf.ThreadPoolExecutor(2) if concurrent else None
    while True:
        t = c.get(f"/api/session/{s}/trial").json()
        if t["done"]:
            break
        per = {}
        for eye in eyes:
            def get(slot):
                url = t["images"][slot] if eye is None else t["images"][slot][f"{eye}_eye"]
                t0 = time.perf_counter()
                r = c.get(url)
                return r, time.perf_counter() - t0, time.perf_counter()
            if pool is not None:
                got = dict(zip(slots, pool.map(get, slots)))
            else:
                got = {slot: get(slot) for slot in (slots if t["trial_index"] % 2 else slots[::-1])}
            per[eye] = got
        t0 = time.perf_counter()
        both = c.get(t["stimuli"]["url"])
        records.append({"trial": t, "per": per, "both": both, "both_s": time.perf_counter() - t0})
        r = c.post(f"/api/session/{s}/responses", json={"response_id": str(uuid.uuid4()),
                                                        "trial_index": t["trial_index"], "choice": slots[0],
                                                        "rt_ms": 500})
        assert r.status_code == 201
    if pool is not None:
        pool.shutdown()
    return records


def _check_records(records, photo_slot, where, eyes=(None,), slots=("left", "right")):
    """Every observable equal for the two slots on every trial; classifiers at chance."""
    photo_left = [photo_slot[r["trial"]["trial_index"]] == 0 for r in records]
    features = {"body length": [], "header values": [], "download time": [], "completion order": [],
                "combined body time": [], "combined body length": []}
    for rec in records:
        w, h = rec["trial"]["width"], rec["trial"]["height"]
        for eye in eyes:
            (rl, tl, el), (rr, tr, er) = (rec["per"][eye][s] for s in slots)
            assert rl.status_code == rr.status_code == 200, where
            assert len(rl.content) == len(rr.content) == bmp_length(w, h), where
            assert _visible_headers(rl) == _visible_headers(rr), (where, rl.headers, rr.headers)
            assert not {"etag", "last-modified"} & set(rl.headers), where
            assert rl.content[:54] == rr.content[:54], where        # the BMP headers, byte for byte
            features["body length"].append(len(rl.content) - len(rr.content))
            features["header values"].append(hash(tuple(_visible_headers(rl))) - hash(tuple(_visible_headers(rr))))
            features["download time"].append(tl - tr)
            features["completion order"].append(el - er)
        both = rec["both"]
        assert both.status_code == 200 and len(both.content) == len(eyes) * 2 * 3 * w * h, where
        assert not {"etag", "last-modified"} & set(both.headers), where
        features["combined body time"].append(rec["both_s"])
        features["combined body length"].append(len(both.content))
    # the headers of the combined body are the same on every trial (one pixel size in this set)
    assert len({tuple(_visible_headers(r["both"])) for r in records}) == 1, where
    if len(eyes) > 1:   # one guess per trial: average the eyes
        features = {k: (np.reshape(v, (len(records), -1)).mean(axis=1) if len(v) != len(records) else v)
                    for k, v in features.items()}
    # single-response features are compared against their median (no left/right within them)
    for k in ("combined body time", "combined body length"):
        features[k] = np.asarray(features[k]) - np.median(features[k])
    _assert_chance(features, photo_left, where)
    return photo_left


def test_positive_control_png_sizes_give_the_photograph_away(attack_toml):
    """On this set, PNG-compressed stimuli of one pixel size would betray the photograph."""
    ps = load_pairs(attack_toml)
    sizes = []
    for pair in ps.pairs:
        rendered = len(prepare_image(pair.rendered, (64, 48)))
        photo = len(prepare_image(pair.photo, (64, 48)))
        sizes.append((rendered, photo))
    assert all(p > 2 * r for r, p in sizes), sizes
    rng = np.random.default_rng(0)
    photo_left = rng.random(200) < 0.5
    diffs = [(p - r) if left else (r - p) for left, (r, p) in zip(photo_left, sizes * 10)]
    k, n = _classify(diffs, photo_left)
    assert k == n   # the classifier of this file finds a size leak on every trial


def test_in_process_client_sees_nothing_but_pixels(attack_toml, tmp_path):
    db = tmp_path / "r.sqlite"
    app = create_app(load_pairs(attack_toml), db, cache_dir=tmp_path / "cache")
    with TestClient(app) as c:
        for i in range(5):
            records = _fetch_trials(c, f"A{i}")
            photo = _photo_slots(db, f"A{i}")
            if i == 0:
                all_records, all_photo = records, dict(photo)
            else:
                offset = len(all_records)
                for r in records:
                    r["trial"] = {**r["trial"], "trial_index": r["trial"]["trial_index"] + offset}
                all_photo.update({t + offset: s for t, s in photo.items()})
                all_records += records
    assert len(all_records) == 5 * N_PAIRS * REPS
    _check_records(all_records, all_photo, "in-process httpx")


def test_real_server_on_loopback_sees_nothing_but_pixels(attack_toml, tmp_path, server_factory):
    import httpx

    db = tmp_path / "r.sqlite"
    srv = server_factory(attack_toml, db).start()
    all_records, all_photo = [], {}
    with httpx.Client(base_url=srv.url, timeout=30) as c:
        for i in range(3):
            records = _fetch_trials(c, f"U{i}", concurrent=True)
            offset = len(all_records)
            for r in records:
                r["trial"] = {**r["trial"], "trial_index": r["trial"]["trial_index"] + offset}
            all_photo.update({t + offset: s for t, s in _photo_slots(db, f"U{i}").items()})
            all_records += records
    _check_records(all_records, all_photo, "uvicorn on 127.0.0.1")


def test_stereo_trials_see_nothing_but_pixels(tmp_path):
    toml = _attack_pairs(tmp_path / "stereo", n_pairs=10, stereo=True)
    db = tmp_path / "s.sqlite"
    app = create_app(load_pairs(toml), db, cache_dir=tmp_path / "cache")
    with TestClient(app) as c:
        records = _fetch_trials(c, "S0", slots=("top", "bottom"), eyes=("left", "right"))
        records += _fetch_trials(c, "S1", slots=("top", "bottom"), eyes=("left", "right"))
    photo = _photo_slots(db, "S0")
    photo.update({t + 20: s for t, s in _photo_slots(db, "S1").items()})
    for k, r in enumerate(records):
        r["trial"] = {**r["trial"], "trial_index": k}
        assert r["trial"]["stimuli"]["views"] == [["top", "left_eye"], ["top", "right_eye"],
                                                  ["bottom", "left_eye"], ["bottom", "right_eye"]]
    _check_records(records, photo, "stereo", eyes=("left", "right"), slots=("top", "bottom"))


@pytest.mark.browser
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"{CHROMIUM} not found: install Debian's chromium")
def test_participant_page_in_chromium_sees_nothing_but_pixels(attack_toml, tmp_path, server_factory):
    """A whole session in the real page; every response the browser receives is recorded, and
    in each trial the page's own JavaScript fetches both per-slot images and times them."""
    from playwright.sync_api import expect, sync_playwright

    db = tmp_path / "r.sqlite"
    srv = server_factory(attack_toml, db).start()
    seen = []
    probes = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.set_default_timeout(30_000)
            expect.set_options(timeout=30_000)
            page.on("response", lambda r: seen.append(r) if "/api/session/" in r.url and (
                "/stimuli/" in r.url or "/image/" in r.url) else None)
            page.goto(srv.url + "/")
            page.fill("#participant-id", "CHROME1")
            page.check("#consent")
            page.click("#start")
            page.click("#begin")
            for i in range(N_PAIRS * REPS):
                expect(page.locator("body[data-phase=awaiting-response]")).to_have_count(1)
                # what a participant's devtools console can do: fetch both images, time them
                probes.append(page.evaluate("""async () => {
                    const t = state.trial;
                    const one = async (slot) => {
                        const t0 = performance.now();
                        const r = await fetch(t.images[slot], {cache: "no-store"});
                        const n = (await r.arrayBuffer()).byteLength;
                        return {status: r.status, headers: [...r.headers].filter(([k]) => k !== "date"),
                                length: n, ms: performance.now() - t0, end: performance.now()};
                    };
                    const [l, r] = await Promise.all([one("left"), one("right")]);
                    return {trial: t.trial_index, left: l, right: r, width: t.width, height: t.height};
                }"""))
                expect(page.locator("#counter")).to_have_text(f"{i + 1} / {N_PAIRS * REPS}")
                if i == 0:   # the canvases show exactly the served sRGB pixels (no colour management)
                    same = page.evaluate("""async () => {
                        const t = state.trial, n = 3 * t.width * t.height;
                        const raw = new Uint8Array(await (await fetch(t.stimuli.url)).arrayBuffer());
                        const canvases = [...document.querySelectorAll("#stage canvas")];
                        return canvases.map((c, k) => {
                            const px = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
                            for (let i = 0, j = 0; i < n; i += 3, j += 4)
                                if (px[j] !== raw[k * n + i] || px[j + 1] !== raw[k * n + i + 1] ||
                                    px[j + 2] !== raw[k * n + i + 2]) return false;
                            return true;
                        });
                    }""")
                    assert same == [True, True], same
                page.keyboard.press("ArrowLeft" if i % 2 else "ArrowRight")
            expect(page.locator("#screen-done")).to_be_visible()
            bodies = [(r.url, r.status, r.all_headers(), len(r.body()), r.request.timing) for r in seen]
        finally:
            browser.close()
    photo = _photo_slots(db, "CHROME1")
    photo_left = [photo[p["trial"]] == 0 for p in probes]
    w, h = probes[0]["width"], probes[0]["height"]
    for p in probes:
        assert p["left"]["status"] == p["right"]["status"] == 200
        assert p["left"]["length"] == p["right"]["length"] == bmp_length(w, h)
        assert p["left"]["headers"] == p["right"]["headers"]
    # the page itself received one raw body per trial, all alike but for the pixels
    page_bodies = list({b[0]: b for b in reversed(bodies) if "/stimuli/" in b[0]}.values())[::-1]  # first per URL
    assert len(page_bodies) == N_PAIRS * REPS
    assert {b[3] for b in page_bodies} == {2 * 3 * w * h}
    assert {b[1] for b in page_bodies} == {200}
    hdrs = {tuple(sorted((k, v) for k, v in b[2].items() if k != "date")) for b in page_bodies}
    assert len(hdrs) == 1 and not {"etag", "last-modified"} & {k for k, _ in next(iter(hdrs))}
    body_ms = np.array([b[4]["responseEnd"] - b[4]["requestStart"] for b in page_bodies])
    body_trial = [int(b[0].rsplit("/", 1)[1]) for b in page_bodies]
    _assert_chance({"download time (devtools)": [p["left"]["ms"] - p["right"]["ms"] for p in probes],
                    "completion order (devtools)": [p["left"]["end"] - p["right"]["end"] for p in probes],
                    "body length (devtools)": [p["left"]["length"] - p["right"]["length"] for p in probes]},
                   photo_left, "chromium page")
    _assert_chance({"page's combined body time": body_ms - np.median(body_ms)},
                   [photo[t] == 0 for t in body_trial], "chromium page")
