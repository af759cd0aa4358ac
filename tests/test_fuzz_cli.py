"""Issue 21 item 7: the fuzzing kept as a test.

A seeded generator makes a few hundred bad inputs the way a careless or hostile user would —
mutated recipes, material CSV/YAML files, ellipsometry files (plain CSV and Woollam), microstructure
cells and CLI arguments — and runs each in-process. Every case must end in

- success (exit 0), or
- exit 2 with exactly one stderr line starting ``error:`` (the CLI's one voice),

never a traceback (any other exception escaping ``nmmm.cli.main``), never a hang (each case runs
under an alarm of CASE_SECONDS). Recipe texts go through the public loader (``load_recipe``),
which must return a Recipe or raise an NmmmError. The whole file runs in well under 60 s.
"""

from __future__ import annotations

import contextlib
import io
import random
import signal
from pathlib import Path

import numpy as np
import pytest

from nmmm.errors import NmmmError

SEED = 21
CASE_SECONDS = 20
EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "nmmm" / "recipes" / "examples"
NASTY_NUMBERS = ["0", "-1", "-0", "1e308", "-1e308", "1e-300", "nan", "inf", "-inf", "1e9", "abc", '""',
                 "0x10", "1_0", "true", "[]", "{}", "5e5", "-1.5", "3.7", "99999999999999999999"]
NASTY_BYTES = [b"\x00", b"\xff\xfe", b"\xef\xbb\xbf", b"\r", b"\t", b"\x1b[31m", "µ".encode(), b"\xe9",
               b"\n\n", b";", b",,,", b"#", b"'", b'"', b"[", b"]", b"=", b"{{"]


class Hang(BaseException):
    """The alarm: a BaseException, so no ``except Exception`` in the code under test swallows it."""


@contextlib.contextmanager
def alarm(seconds):
    def on_alarm(signum, frame):
        raise Hang(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def mutate_text(rng: random.Random, text: str) -> bytes:
    """One to three random edits of ``text``: a number replaced by a nasty one, a line dropped,
    duplicated or cut mid-way, a key renamed, bytes inserted, the text truncated."""
    lines = text.splitlines()
    for _ in range(rng.randint(1, 3)):
        if not lines:
            break
        op = rng.randrange(7)
        i = rng.randrange(len(lines))
        line = lines[i]
        if op == 0:
            import re

            nums = list(re.finditer(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", line))
            if nums:
                m = rng.choice(nums)
                lines[i] = line[: m.start()] + rng.choice(NASTY_NUMBERS) + line[m.end():]
        elif op == 1:
            del lines[i]
        elif op == 2:
            lines.insert(i, line)
        elif op == 3:
            lines[i] = line[: rng.randint(0, max(len(line) - 1, 0))]
        elif op == 4 and "=" in line:
            k, v = line.split("=", 1)
            lines[i] = k.strip() + rng.choice(["x", "_", ".a", " b"]) + " =" + v
        elif op == 5:
            lines[i] = line + rng.choice(NASTY_BYTES).decode("latin-1")
        else:
            lines = lines[: i + 1]
            lines[-1] = lines[-1][: rng.randint(0, len(lines[-1]))]
    data = "\n".join(lines).encode("utf-8", "surrogateescape")
    if rng.random() < 0.15:
        pos = rng.randint(0, len(data))
        data = data[:pos] + rng.choice(NASTY_BYTES) + data[pos:]
    return data


#: stdout of the latest :func:`run_cli` call (for the checks of a command that exited 0)
LAST_STDOUT = [""]


def run_cli(argv):
    """(exit status, stderr lines) of ``nmmm argv`` in-process; raises what escapes main. Its stdout
    is kept in ``LAST_STDOUT[0]``."""
    from nmmm.cli import main

    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), alarm(CASE_SECONDS):
        rc = main([str(a) for a in argv])
    LAST_STDOUT[0] = out.getvalue()
    return rc, [ln for ln in err.getvalue().splitlines() if ln.strip()]


def assert_shown_nk_physical(case, stdout):
    """``materials show`` that exited 0 printed a finite table with n > 0 and k >= 0."""
    import re

    rows = [ln.split() for ln in stdout.splitlines() if re.match(r"^\s+[-+0-9.]+\s+[-+0-9.naif]+\s+[-+0-9.naif]+\s*$", ln)]
    assert rows, f"{case}: exit 0 but no n, k table in {stdout[:300]!r}"
    vals = np.array([[float(x) for x in r] for r in rows])
    assert np.isfinite(vals).all(), f"{case}: non-finite values shown: {rows[:5]}"
    assert (vals[:, 0] > 0).all() and (vals[:, 1] > 0).all() and (vals[:, 2] >= 0).all(), \
        f"{case}: unphysical wavelength, n or k shown: {rows[:5]}"


def assert_clean(case, rc, err, no_match_ok=False):
    """Exit 0, or 2 with one 'error:' line; ``no_match_ok``: a search that finds nothing exits 1
    with one line, as grep does (not an input error)."""
    assert rc in ((0, 1, 2) if no_match_ok else (0, 2)), f"{case}: exit {rc}, stderr {err[-3:]}"
    if rc != 0:
        errors = [ln for ln in err if ln.startswith("error:")]
        assert len(errors) == 1, f"{case}: expected one 'error:' line, got {err[-5:]}"
        assert "Traceback" not in "\n".join(err), f"{case}: traceback on stderr"


MATERIAL_CSV = """# name: fuzz glass
# reference: test
wavelength_nm,n,k
400,1.47,0
500,1.46,0.0001
600,1.458,0
700,1.455,0
800,1.453,0
"""

MATERIAL_YAML = """REFERENCES: test
DATA:
  - type: tabulated nk
    data: |
        0.40 1.47 0.0
        0.50 1.46 0.0001
        0.60 1.458 0.0
        0.80 1.453 0.0
"""

WOOLLAM = "fuzz film\nVASEmethod[EllipsometerType=4]\nnm\n" + "".join(
    f"E {w} 70 {20 + 0.01 * w:.3f} {100 + 0.02 * w:.3f} 0.01 0.05\n" for w in range(400, 801, 25))

ELLI_CSV = "wavelength_nm,angle_deg,psi_deg,delta_deg\n" + "".join(
    f"{w},70,{20 + 0.01 * w:.3f},{100 + 0.02 * w:.3f}\n" for w in range(400, 801, 25))


def test_fuzz_recipes_load_or_refuse_cleanly():
    from nmmm.recipes.schema import load_recipe

    rng = random.Random(SEED)
    texts = sorted(EXAMPLES.glob("*.toml"))
    assert texts, f"no shipped recipes under {EXAMPLES}"
    sources = [p.read_text(encoding="utf-8") for p in texts]
    kinds = {"ok": 0, "error": 0}
    for n in range(150):
        data = mutate_text(rng, rng.choice(sources))
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            text = None
        try:
            with alarm(CASE_SECONDS):
                if text is None:  # bytes that are not UTF-8: through a file, as a user would
                    import tempfile

                    with tempfile.TemporaryDirectory() as tmp:
                        p = Path(tmp) / "r.toml"
                        p.write_bytes(data)
                        load_recipe(p)
                else:
                    load_recipe(text)
            kinds["ok"] += 1
        except NmmmError as exc:
            assert str(exc).strip(), f"case {n}: empty error message"
            kinds["error"] += 1
        except Hang:
            pytest.fail(f"recipe case {n} hung: {data[:200]!r}")
        except Exception as exc:  # noqa: BLE001 - that is what the test is for
            pytest.fail(f"recipe case {n}: {type(exc).__name__}: {exc} for {data[:300]!r}")
    assert kinds["error"] > 30 and kinds["ok"] > 10, kinds  # the generator does make bad and good inputs


@pytest.mark.parametrize("kind", ["material_csv", "material_yaml", "woollam", "ellipsometry_csv"])
def test_fuzz_data_files_through_the_cli(tmp_path, kind):
    rng = random.Random(f"{SEED}-{kind}")
    base, suffix, argv = {
        "material_csv": (MATERIAL_CSV, ".csv", ["materials", "show"]),
        "material_yaml": (MATERIAL_YAML, ".yml", ["materials", "show"]),
        "woollam": (WOOLLAM, ".dat", ["ellipsometry", "pseudo"]),
        "ellipsometry_csv": (ELLI_CSV, ".csv", ["ellipsometry", "pseudo"]),
    }[kind]
    codes = {0: 0, 2: 0}
    for n in range(45):
        data = mutate_text(rng, base)
        p = tmp_path / f"case{n}{suffix}"
        p.write_bytes(data)
        extra = ["-o", str(tmp_path / f"out{n}.csv")] if argv[0] == "ellipsometry" else []
        case = f"{kind} case {n} ({data[:160]!r})"
        try:
            rc, err = run_cli(argv + [p] + extra)
        except Hang:
            pytest.fail(f"{case} hung")
        except BaseException as exc:  # noqa: BLE001
            pytest.fail(f"{case}: {type(exc).__name__} escaped the CLI: {exc}")
        assert_clean(case, rc, err)
        if rc == 0 and argv[0] == "materials":
            assert_shown_nk_physical(case, LAST_STDOUT[0])
        codes[rc] += 1
    assert codes[2] > 5, codes


def _cli_arg_cases(rng: random.Random, tmp_path: Path):
    cell = tmp_path / "cell.npz"
    if not cell.exists():
        from nmmm.microstructure import Microstructure, save_microstructure

        lab = np.zeros((16, 16), dtype=np.uint8)
        lab[:8] = 1
        save_microstructure(Microstructure(lab, voxel_nm=10.0), cell)
    num = lambda: rng.choice(NASTY_NUMBERS + ["5", "380", "780", "10", "0.5"])  # noqa: E731
    key = lambda: rng.choice(["main/SiO2/Malitson", "main/Au/Johnson", "nope/none", "", "main/SiO2", "../etc"])  # noqa: E731
    makers = [
        lambda: ["ema", "mix", "--host", key(), "--inclusion",
                 f"{key()}:{num()}" + rng.choice(["", f":{rng.choice(['sphere', 'x', 'spheroid=2', ''])}",
                                                  f":sphere:{num()}"]),
                 "--start-nm", num(), "--stop-nm", num(), "--step-nm", num(),
                 "--method", rng.choice(["maxwell_garnett", "bruggeman", "looyenga", "mg", ""])],
        lambda: ["materials", "show", key(), "--points", num()],
        lambda: ["homogenize", "run", str(cell), "--eps", f"0={num()}", "--eps", f"1={num()}" + rng.choice(["", "+1j", "i"]),
                 "--tol", num(), "--max-minutes", num()],
        lambda: ["materials", "search", rng.choice(["Fe2O3", "", "%", "a" * 300, "TiO2", "\x00"])],
        lambda: ["ellipsometry", "simulate", "--model", str(tmp_path / "none.toml"), "-o", str(tmp_path / "s.csv")],
        lambda: [rng.choice(["run", "sweep", "compare"]), rng.choice(["no_such_recipe", str(tmp_path), ""])],
    ]
    return rng.choice(makers)()


def test_fuzz_cli_arguments(tmp_path):
    rng = random.Random(f"{SEED}-args")
    codes = {0: 0, 2: 0}
    for n in range(120):
        argv = _cli_arg_cases(rng, tmp_path)
        case = f"args case {n}: nmmm {' '.join(map(str, argv))[:200]}"
        try:
            rc, err = run_cli(argv)
        except Hang:
            pytest.fail(f"{case} hung")
        except BaseException as exc:  # noqa: BLE001
            pytest.fail(f"{case}: {type(exc).__name__} escaped the CLI: {exc}")
        assert_clean(case, rc, err, no_match_ok=argv[:2] == ["materials", "search"])
        if rc == 0 and argv[:2] == ["materials", "show"]:
            assert_shown_nk_physical(case, LAST_STDOUT[0])
        codes[rc] = codes.get(rc, 0) + 1
    assert codes[2] > 20 and codes[0] > 3, codes


def test_found_by_the_fuzzer_yaml_row_cut_off(tmp_path):
    """A refractiveindex.info YAML whose last data row was cut off (two numbers of three) raised
    numpy's ValueError (inhomogeneous shape) through the CLI; now one error line naming the row."""
    p = tmp_path / "cut.yml"
    p.write_text(MATERIAL_YAML.rstrip()[:-4] + "\n")
    rc, err = run_cli(["materials", "show", p])
    assert rc == 2 and len(err) == 1 and "row 4 has 2 numbers" in err[0] and "needs 3 per row" in err[0]
