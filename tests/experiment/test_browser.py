"""A whole session driven in a real browser (Debian's chromium through Playwright).

The server is a real subprocess; it is killed (SIGKILL) while a response is on its way and
restarted. No acknowledged response is lost, the unacknowledged one is re-sent by the page
with the same id and stored once, and after a reload the participant resumes where they
stopped. (Killing between trials is covered by test_server.py.)
"""

from __future__ import annotations

import os
import time

import pytest
from experiment_helpers import CHROMIUM, CHROMIUM_ARGS, make_pairs

from nmmm.experiment.storage import read_responses

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM),
                       reason=f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium)"),
]


def _wait_rows(db, n, timeout_s=20):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if db.exists() and len(read_responses(db)) >= n:
            return
        time.sleep(0.05)
    raise AssertionError(f"expected {n} stored responses")


def test_browser_session_with_server_kills_and_resume(tmp_path, server_factory):
    from playwright.sync_api import expect, sync_playwright

    toml = make_pairs(tmp_path, n_pairs=4, blank_ms=150, viewing_distance_cm=57)
    db = tmp_path / "responses.sqlite"
    srv = server_factory(toml, db).start()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            # a HiDPI display: 2 device pixels per CSS pixel
            page = browser.new_page(viewport={"width": 1280, "height": 800}, device_scale_factor=2)
            stimuli_urls = []
            page.on("request", lambda req: stimuli_urls.append(req.url) if "/api/session/" in req.url and (
                "/stimuli/" in req.url or "/image/" in req.url) else None)
            page.set_default_timeout(30_000)
            expect.set_options(timeout=30_000)   # the CI machine may be busy
            page.goto(srv.url + "/")

            # consent and calibration note; starting without consent is refused
            expect(page.locator("#screen-consent")).to_be_visible()
            expect(page.locator("#calibration-note")).to_contain_text("57 cm")
            expect(page.locator("#consent-text")).to_contain_text("photograph")
            page.fill("#participant-id", "B01")
            page.evaluate("document.getElementById('consent').required = false")
            page.click("#start")
            expect(page.locator("#error")).to_contain_text("consent")
            page.check("#consent")
            page.click("#start")
            expect(page.locator("#screen-ready")).to_be_visible()
            expect(page.locator("#ready-progress")).to_contain_text("4 trials")
            page.click("#begin")

            def shown_trial():
                expect(page.locator("#stage.shown")).to_be_visible()
                expect(page.locator("body[data-phase=awaiting-response]")).to_have_count(1)
                left, right = page.locator("#choice-left"), page.locator("#choice-right")
                bl, br = left.bounding_box(), right.bounding_box()
                assert (round(bl["width"]), round(bl["height"])) == (round(br["width"]), round(br["height"]))
                # one image pixel per device pixel: 48-px-wide stimuli are 24 CSS px wide at DPR 2
                widths = page.eval_on_selector_all(
                    "#stage canvas", "els => els.map(e => [e.width, e.getBoundingClientRect().width])")
                assert widths == [[48, 24], [48, 24]], widths
                # the page fetched the images as one raw body per trial, nothing named after them
                assert stimuli_urls and all("/stimuli/" in u for u in stimuli_urls)
                tails = [u.split("/api/session/", 1)[1].split("/", 1)[1] for u in stimuli_urls]  # after the token
                assert not any(w in t for t in tails for w in ("photo", "render", ".jpg", "p0", "r0")), tails
                return page.locator("#counter").inner_text()

            # trial 1: click the left image
            assert shown_trial() == "1 / 4"
            page.click("#choice-left")
            _wait_rows(db, 1)
            assert shown_trial() == "2 / 4"
            # the server dies while the answer to trial 2 is being sent
            srv.kill()
            page.keyboard.press("ArrowRight")
            expect(page.locator("#status")).to_contain_text("retrying")
            assert len(read_responses(db)) == 1          # nothing committed while it is down
            srv.start()
            assert shown_trial() == "3 / 4"              # the pending answer arrived
            _wait_rows(db, 2)

            # the participant closes / reloads the page: resume at trial 3
            page.reload()
            expect(page.locator("#screen-ready")).to_be_visible()
            expect(page.locator("#ready-heading")).to_have_text("Welcome back")
            expect(page.locator("#ready-progress")).to_contain_text("2 of 4")
            page.click("#begin")
            assert shown_trial() == "3 / 4"
            page.keyboard.press("ArrowLeft")
            assert shown_trial() == "4 / 4"
            page.click("#choice-right")
            expect(page.locator("#screen-done")).to_be_visible()
            page.reload()
            expect(page.locator("#screen-done")).to_be_visible()
        finally:
            browser.close()

    rows = read_responses(db)
    assert [r["trial_index"] for r in rows] == [0, 1, 2, 3]
    assert [r["chosen_slot"] for r in rows] == [0, 1, 0, 1]
    assert len({r["response_id"] for r in rows}) == 4
    assert all(r["rt_ms"] > 0 for r in rows)
    assert {r["pair_id"] for r in rows} == {f"plate-{i}" for i in range(4)}
