"""Issue 21's census: every item of its *Found* list (tracebacks, silently wrong results, hangs),
tried against the current code and classified.

Outcomes: ``clean`` (an NmmmError, or through the CLI exit 2 with one ``error:`` line),
``warned`` (a UserWarning that says what would be right), ``silent`` (accepted without a word),
``traceback`` (any other exception), ``hang`` (no answer within the alarm). Each case states the
outcome the issue asks for; the test fails when another comes out.

``python tests/test_bad_inputs_issue21.py`` prints the counts per category (the note's re-count).
Integrity and confinement items (locks, atomic folders, verified sweeps, confinement, no echo) are
tested in tests/recipes/test_bad_input_integrity.py; the disk-full run there as well.
"""

from __future__ import annotations

import contextlib
import io
import re
import signal
import warnings
from pathlib import Path

import numpy as np
import pytest

from nmmm.errors import NmmmError

ALARM_S = 30


class _Hang(Exception):
    pass


@contextlib.contextmanager
def _alarm(seconds=ALARM_S):
    def on_alarm(signum, frame):
        raise _Hang()

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


class _CliClean(Exception):
    pass


def cli(*argv):
    """Run nmmm in-process; exit 2 with one 'error:' line -> _CliClean, exit 0 -> returns,
    anything else -> AssertionError (classified as a traceback)."""
    from nmmm.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main([str(a) for a in argv])
    lines = [ln for ln in err.getvalue().splitlines() if ln.strip() and not ln.startswith("warning")]
    errors = [ln for ln in lines if ln.startswith("error:")]
    if rc == 2 and len(errors) == 1 and "Traceback" not in err.getvalue():
        raise _CliClean(errors[0])
    if rc != 0:
        raise AssertionError(f"exit {rc}: {lines[-3:]}")


#: what the warning of each case expected to warn must say: another warning does not count
WARN_TEXT = {
    "coherent 1 m layer in Stack": r"layer 0 .* is coherent but its interference fringes",
    "spectral power file 500-510 nm only": r"covers only 500-510 nm",
    "Woollam file with a NaN row": r"NaN or infinite value left out \(line 7\)",
    "Woollam file truncated mid-line": r"truncated line\(s\) left out.*line 7",
}


def classify(fn, tmp: Path, warn_text: str | None = None) -> str:
    """'clean' (a one-line error), 'hang', 'traceback', 'warned' (a UserWarning matching
    ``warn_text``; without it, any), 'other warning' (UserWarnings, none matching) or 'silent'."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _alarm():
                fn(tmp)
        except (NmmmError, _CliClean):
            return "clean"
        except _Hang:
            return "hang"
        except Exception:  # noqa: BLE001 - what the census counts
            return "traceback"
    user = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    if any(warn_text is None or re.search(warn_text, m) for m in user):
        return "warned"
    return "other warning" if user else "silent"


def _w(tmp, name, data):
    p = tmp / name
    p.write_bytes(data if isinstance(data, bytes) else data.encode())
    return p


CSV_HEAD = "wavelength_nm,n,k\n"


def _csv(rows):
    return CSV_HEAD + "".join(f"{w},{n},{k}\n" for w, n, k in rows)


WOOLLAM_HEAD = "film\nVASEmethod[EllipsometerType=4]\nnm\n" + "".join(
    f"E {w} 70 {26 + 0.001 * w:.3f} {120 + 0.01 * w:.3f} 0.01 0.05\n" for w in range(600, 660, 20))


def _mie_grid(tmp):
    from nmmm.layers import mie

    mie(np.full(20000, 2.0 + 0.01j)[:, None], 1.5, np.linspace(100, 2000, 2000)[None, :],
        np.full(20000, 550.0)[:, None])


def _pairs_same(tmp):
    from PIL import Image

    from nmmm.experiment.pairs import load_pairs

    Image.fromarray(np.zeros((8, 12, 3), np.uint8)).save(tmp / "a.png")
    load_pairs(_w(tmp, "pairs.toml", "[[pair]]\nrendered = 'a.png'\nphoto = 'a.png'\n"))


def _stats_alpha(tmp):
    from nmmm.experiment.stats import analyse_responses

    analyse_responses([{"participant_id": "p", "pair_id": "a", "correct": 1, "n_trials": 1}], alpha=2)


def _fft_4096(tmp):
    from nmmm.homogenize.fft import fft_permittivity

    lab = np.random.default_rng(0).integers(0, 3, (4096, 4096)).astype(np.uint8)
    fft_permittivity(lab, {0: 2.25, 1: -50 + 2j, 2: 3.0}, check_periodic=False)


CAUCHY_ON_SI = """
name = "Cauchy film on Si"
[substrate]
material = "main/Si/Green-2008"
[[layers]]
name = "film"
thickness_nm = {value = %s, min = 1000, max = 1400}
model = "cauchy"
A = {value = %s, min = 1.3, max = 1.9}
B_um2 = {value = 0.006, min = -0.05, max = 0.1}
"""


def _ellipsometry_local_minimum(tmp):
    """The 1.2 µm Cauchy film fitted from a start 30 nm / 0.05 in A off (issue: MSE 446-490, exit 0)."""
    import tomllib

    from nmmm.ellipsometry.data import EllipsometryData
    from nmmm.ellipsometry.fit_start import check_fit_quality, thickness_prescan
    from nmmm.ellipsometry.model import EllipsometryModel

    truth = EllipsometryModel.from_dict(tomllib.loads(CAUCHY_ON_SI % (1200.0, 1.55)))
    start = EllipsometryModel.from_dict(tomllib.loads(CAUCHY_ON_SI % (1230.0, 1.60)))
    data = EllipsometryData.from_model(truth.build(), np.arange(300.0, 1001.0, 5.0), [65.0, 75.0], 0.02, 0.05,
                                       noise_seed=5)
    model, _ = thickness_prescan(start, data)
    bad = check_fit_quality(model.fit(data))
    if bad:  # what --strict turns into exit 2; without the pre-scan this is the outcome
        raise NmmmError(bad)


CASES = {
    # ---- tracebacks ---------------------------------------------------------------------------
    "recipe nested 5000 deep": ("traceback", "clean", lambda t: cli("run", _w(t, "deep.toml", "a = " + "[" * 5000 + "]" * 5000), "-o", t / "o")),
    "non-UTF-8 recipe": ("traceback", "clean", lambda t: cli("run", _w(t, "bin.toml", b"name = '\xff\xfe'\n"), "-o", t / "o")),
    "UTF-16 material CSV": ("traceback", "clean", lambda t: cli("materials", "show", _w(t, "u16.csv", _csv([(400, 1.5, 0), (500, 1.5, 0)]).encode("utf-16")))),
    "binary material CSV": ("traceback", "clean", lambda t: cli("materials", "show", _w(t, "bin.csv", bytes(range(256)) * 4))),
    "recipe path is a directory": ("traceback", "clean", lambda t: cli("run", t, "-o", t / "o")),
    "CSV wavelength 0": ("traceback", "clean", lambda t: cli("materials", "show", _w(t, "w0.csv", _csv([(0, 1.5, 0), (500, 1.5, 0)])))),
    "YAML material file that is a list": ("traceback", "clean", lambda t: cli("materials", "show", _w(t, "l.yml", "- 1\n- 2\n"))),
    "ema mix --inclusion KEY:abc": ("traceback", "clean", lambda t: cli("ema", "mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:abc")),
    "--step-nm 1e-9": ("traceback", "clean", lambda t: cli("ema", "mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:0.001", "--step-nm", "1e-9")),
    "materials show --points 1e9": ("traceback", "clean", lambda t: cli("materials", "show", "main/SiO2/Malitson", "--points", "1000000000")),
    "materials show --points -5": ("traceback", "clean", lambda t: cli("materials", "show", "main/SiO2/Malitson", "--points", "-5")),
    "sweep --vary ...:10000000": ("traceback", "clean", lambda t: cli("sweep", "hematite_paint", "--vary", "pigments.0.fraction=0.01:0.2:10000000", "-o", t / "s")),
    "maxwell_garnett shape mismatch": ("traceback", "clean", lambda t: __import__("nmmm.ema", fromlist=["x"]).maxwell_garnett(np.ones(3) * 4, np.ones(4) * 2, 0.1)),
    "mie shape mismatch": ("traceback", "clean", lambda t: __import__("nmmm.layers", fromlist=["x"]).mie(np.ones(3) * 2, 1.5, np.ones(4) * 100, np.ones(5) * 500)),
    # ---- silently wrong or accepted -----------------------------------------------------------
    "spectra_to_lab of a negative spectrum": ("silent", "clean", lambda t: __import__("nmmm.colour", fromlist=["x"]).spectra_to_lab(np.arange(380.0, 781.0, 5.0), -np.ones(81))),
    "delta_e2000 with L* = -50": ("silent", "clean", lambda t: __import__("nmmm.colour", fromlist=["x"]).delta_e2000([-50.0, 0, 0], [50.0, 0, 0])),
    "eps_to_nk with Im eps < 0": ("silent", "clean", lambda t: __import__("nmmm.materials", fromlist=["x"]).eps_to_nk(2.0 - 1.0j)),
    "nk_to_eps with k < 0": ("silent", "clean", lambda t: __import__("nmmm.materials", fromlist=["x"]).nk_to_eps(1.5 - 0.1j)),
    "Maxwell Garnett host eps = 0": ("silent", "clean", lambda t: __import__("nmmm.ema", fromlist=["x"]).maxwell_garnett(4.0, 0.0, 0.1)),
    "Bruggeman host eps = 0": ("silent", "clean", lambda t: __import__("nmmm.ema", fromlist=["x"]).bruggeman(4.0, 0.0, 0.1)),
    "coherent 1 m layer in Stack": ("silent", "warned", lambda t: __import__("nmmm.layers", fromlist=["x"]).Stack([(1.5, 1e9)], substrate=1.5).rt(np.arange(400.0, 701.0, 10.0))),
    "material CSV n = 1e308": ("silent", "clean", lambda t: cli("materials", "show", _w(t, "big.csv", _csv([(400, 1e308, 0), (500, 1.5, 0)])))),
    "material CSV n = -1.5": ("silent", "clean", lambda t: cli("materials", "show", _w(t, "neg.csv", _csv([(400, -1.5, 0), (500, 1.5, 0)])))),
    "material CSV n = 0": ("silent", "clean", lambda t: cli("materials", "show", _w(t, "zero.csv", _csv([(400, 0, 0), (500, 1.5, 0)])))),
    "um values under an nm header": ("silent", "clean", lambda t: cli("materials", "show", _w(t, "um.csv", _csv([(0.3, 1.5, 0), (0.9, 1.5, 0)])))),
    "spectral power file all zero": ("silent", "clean", lambda t: __import__("nmmm.appearance.render", fromlist=["x"]).read_spd_csv(_w(t, "z.csv", "wavelength_nm,power\n" + "".join(f"{w},0\n" for w in range(380, 781, 10))))),
    "spectral power file 500-510 nm only": ("silent", "warned", lambda t: __import__("nmmm.appearance.render", fromlist=["x"]).read_spd_csv(_w(t, "n.csv", "wavelength_nm,power\n500,1\n505,2\n510,1\n"))),
    "Woollam file with a NaN row": ("silent", "warned", lambda t: __import__("nmmm.ellipsometry.data", fromlist=["x"]).read_data(_w(t, "nan.dat", WOOLLAM_HEAD + "E 660 70 nan nan 0.01 0.05\n"))),
    "Woollam file truncated mid-line": ("silent", "warned", lambda t: __import__("nmmm.ellipsometry.data", fromlist=["x"]).read_data(_w(t, "cut.dat", WOOLLAM_HEAD + "E 660 70 26.600 1"))),
    "Woollam NaN row, --strict": ("silent", "clean", lambda t: __import__("nmmm.ellipsometry.data", fromlist=["x"]).read_data(_w(t, "nan2.dat", WOOLLAM_HEAD + "E 660 70 nan nan 0.01 0.05\n"), strict=True)),
    "pairs file with the same image twice": ("silent", "clean", _pairs_same),
    "experiment stats --alpha 2": ("silent", "clean", _stats_alpha),
    "ellipsometry fit in a local minimum (after the pre-scan)": ("ellipsometry", "silent", _ellipsometry_local_minimum),
    # ---- hangs ----------------------------------------------------------------------------------
    "sweep -n 0": ("hang", "clean", lambda t: cli("sweep", "hematite_paint", "--vary", "pigments.0.fraction=0.05,0.1", "-n", "0", "-o", t / "s0")),
    "pigment.body_diagonal_nm = 1e9 (mie x > 1e6)": ("hang", "clean", lambda t: __import__("nmmm.layers", fromlist=["x"]).mie(2.0 + 0.1j, 1.5, 1e9, 550.0)),
    "mie on a 20000 x 2000 grid": ("hang", "clean", _mie_grid),
    "fft_permittivity on a 4096^2 three-phase cell": ("hang", "clean", _fft_4096),
}


@pytest.mark.parametrize("name", list(CASES))
def test_issue21_found_item(name, tmp_path):
    category, expected, fn = CASES[name]
    assert expected != "warned" or name in WARN_TEXT, f"{name}: a 'warned' case needs its WARN_TEXT"
    assert classify(fn, tmp_path, WARN_TEXT.get(name)) == expected, f"{category}: {name}"


if __name__ == "__main__":  # the re-count of the note
    import tempfile
    from collections import Counter, defaultdict

    table = defaultdict(Counter)
    for name, (category, expected, fn) in CASES.items():
        with tempfile.TemporaryDirectory() as d:
            got = classify(fn, Path(d), WARN_TEXT.get(name))
        table[category][got] += 1
        print(f"{category:12s} {got:9s} {'ok ' if got == expected else 'BAD'} {name}")
    for category, counts in table.items():
        print(category, dict(counts))
