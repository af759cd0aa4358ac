"""Every line of the README is real (issue 14).

Every fenced ```bash and ```python block of README.md is extracted and run:

- python blocks in a subprocess (``sys.executable``), from a scratch folder;
- shell lines one by one with ``bash -c`` in a scratch folder that holds a copy of
  ``examples/data`` (the README's inputs) and receives every output under ``out/``, in README
  order (later lines read what earlier ones wrote), each asserting exit status 0 and no
  ``Traceback`` in its output. Two kinds of line are run differently, because running them as
  a plain command would not end or needs an optional system library:
  ``nmmm experiment serve`` without ``--check`` serves forever: it is started, its port polled
  on 127.0.0.1, its participant page fetched (HTTP 200), then it is stopped with SIGINT;
  ``nmmm render object`` needs Mitsuba 3 and libLLVM >= 17: where they work it must render,
  where they do not it must print one line with the install command and exit 2;
- the two quick-start commands (``pip install ...``) are not run here: ``.ci/run`` runs them,
  and the test asserts that the README shows exactly those two and that ``.ci/run`` has them.

A runnable block may not hold a placeholder (``...`` or ``…`` as an argument, or Python's
``...``).
"""

from __future__ import annotations

import io
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
import tokenize
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
CI_RUN = ROOT / ".ci" / "run"

#: the README's quick start, exactly; .ci/run runs both
QUICK_START = ('pip install -e . && nmmm demo', 'pip install -e ".[test]" && python -m pytest')

_FENCE = re.compile(r"^```([A-Za-z0-9_+-]*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)


def fenced_blocks(text: str) -> list[tuple[str, str, int, str]]:
    """(language, code, line number of the opening fence, section heading) of every fenced block."""
    blocks = []
    for m in _FENCE.finditer(text):
        before = text[: m.start()]
        headings = re.findall(r"^##+ (.+)$", before, re.M)
        blocks.append((m.group(1).lower(), m.group(2), before.count("\n") + 1, headings[-1] if headings else ""))
    return blocks


BLOCKS = fenced_blocks(README.read_text(encoding="utf-8"))
PYTHON_BLOCKS = [(code, line) for lang, code, line, _ in BLOCKS if lang == "python"]
SHELL_LINES = [(ln.strip(), line + 1 + i, section)
               for lang, code, line, section in BLOCKS if lang in ("bash", "sh", "shell", "console")
               for i, ln in enumerate(code.splitlines()) if ln.strip() and not ln.strip().startswith("#")]
QUICK_LINES = [(ln, n, s) for ln, n, s in SHELL_LINES if ln.startswith("pip install")]
COMMAND_LINES = [(ln, n) for ln, n, s in SHELL_LINES if not ln.startswith("pip install")]


def _words(line: str) -> list[str]:
    return shlex.split(line, comments=True)


def _is_server(line: str) -> bool:
    w = _words(line)
    return w[:3] == ["nmmm", "experiment", "serve"] and "--check" not in w


def _is_render_object(line: str) -> bool:
    return _words(line)[:3] == ["nmmm", "render", "object"]


PLAIN_LINES = [(ln, n) for ln, n in COMMAND_LINES if not _is_server(ln) and not _is_render_object(ln)]


def _env() -> dict:
    env = dict(os.environ)
    # the nmmm console script of this interpreter's environment comes first
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["MPLBACKEND"] = "Agg"
    env.pop("PYTHONSTARTUP", None)
    return env


def _check_ran(what: str, proc, out: str) -> None:
    assert proc.returncode == 0, f"{what} exited with {proc.returncode}:\n{out[-4000:]}"
    assert "Traceback" not in out, f"{what} printed a traceback:\n{out[-4000:]}"


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    """A scratch folder with a copy of examples/data; the README's outputs go to its out/."""
    ws = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples" / "data", ws / "examples" / "data")
    return ws


# --------------------------------------------------------------------------------------
# the README's shape


def test_readme_has_runnable_blocks():
    assert PYTHON_BLOCKS, "the README shows no ```python block"
    assert COMMAND_LINES, "the README shows no nmmm command line"


def test_quick_start_is_exactly_the_two_commands_and_ci_runs_them():
    assert sorted(ln for ln, _, _ in QUICK_LINES) == sorted(QUICK_START), (
        f"the README's pip lines must be exactly the two quick-start commands {QUICK_START}, "
        f"got {[ln for ln, _, _ in QUICK_LINES]}")
    assert {s for _, _, s in QUICK_LINES} == {"Quick start"}, "the quick-start commands belong in '## Quick start'"
    quick_section = [ln for ln, _, s in SHELL_LINES if s == "Quick start"]
    assert quick_section == [ln for ln, _, _ in QUICK_LINES], (
        f"'## Quick start' shows exactly the two commands, nothing else; got {quick_section}")
    ci_lines = [ln.strip() for ln in CI_RUN.read_text().splitlines() if not ln.strip().startswith("#")]
    for cmd in QUICK_START:
        assert any(cmd in ln for ln in ci_lines), f".ci/run does not run the README's quick start {cmd!r}"


def test_no_nmmm_demo_outside_the_quick_start():
    others = [ln for ln, _ in COMMAND_LINES if "nmmm demo" in ln]
    assert not others, f"'nmmm demo' is proven by .ci/run; not shown again: {others}"


@pytest.mark.parametrize("line,lineno", COMMAND_LINES, ids=[f"L{n}" for _, n in COMMAND_LINES])
def test_no_placeholder_in_shell_lines(line, lineno):
    bad = [w for w in _words(line) if "..." in w or "…" in w]
    assert not bad, f"README line {lineno} has a placeholder {bad}: write a real command: {line}"


@pytest.mark.parametrize("code,lineno", PYTHON_BLOCKS, ids=[f"L{n}" for _, n in PYTHON_BLOCKS])
def test_no_placeholder_in_python_blocks(code, lineno):
    toks = list(tokenize.generate_tokens(io.StringIO(code).readline))
    bad = [t.start[0] + lineno for t in toks if t.type == tokenize.OP and t.string == "..."]
    assert not bad, f"README python block at line {lineno} has '...' placeholders at lines {bad}"


# --------------------------------------------------------------------------------------
# running them


@pytest.mark.parametrize("code,lineno", PYTHON_BLOCKS, ids=[f"L{n}" for _, n in PYTHON_BLOCKS])
def test_python_block_runs(code, lineno, tmp_path):
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=_env(), capture_output=True, text=True,
                          timeout=300)
    _check_ran(f"README python block at line {lineno}", proc, proc.stdout + proc.stderr)


def test_command_lines_run(workspace):
    """Every plain command line, in README order, from the scratch folder."""
    assert PLAIN_LINES
    for line, lineno in PLAIN_LINES:
        t0 = time.perf_counter()
        proc = subprocess.run(["bash", "-c", line], cwd=workspace, env=_env(), capture_output=True, text=True,
                              timeout=300)
        out = proc.stdout + proc.stderr
        _check_ran(f"README line {lineno} ({line!r}, {time.perf_counter() - t0:.1f} s)", proc, out)
    assert (workspace / "out").is_dir(), "the README's commands write their outputs under out/"


def _port_of(line: str) -> int:
    w = _words(line)
    return int(w[w.index("--port") + 1]) if "--port" in w else 8000


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


SERVER_LINES = [(ln, n) for ln, n in COMMAND_LINES if _is_server(ln)]


@pytest.mark.parametrize("line,lineno", SERVER_LINES, ids=[f"L{n}" for _, n in SERVER_LINES])
def test_server_line_serves_then_stops(line, lineno, workspace):
    """The server is started as the README writes it, answers on its port, and stops on Ctrl-C."""
    port = _port_of(line)
    if not _port_free(port):
        pytest.skip(f"port {port} of README line {lineno} is taken by another program on this machine")
    proc = subprocess.Popen(["bash", "-c", f"exec {line}"], cwd=workspace, env=_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        status = None
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5) as r:
                    status = r.status
                break
            except OSError:
                time.sleep(0.3)
        assert proc.poll() is None, f"README line {lineno} stopped early:\n{proc.stdout.read()}"
        assert status == 200, f"README line {lineno}: no participant page on port {port} within 90 s"
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert "Traceback" not in out, f"README line {lineno} printed a traceback:\n{out}"
    assert f"http://127.0.0.1:{port}/" in out, f"README line {lineno} did not print its address:\n{out}"


OBJECT_LINES = [(ln, n) for ln, n in COMMAND_LINES if _is_render_object(ln)]


def _mitsuba_works() -> bool:
    code = "from nmmm.appearance.render.mitsuba_paint import require_mitsuba; require_mitsuba()"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120).returncode == 0


@pytest.mark.parametrize("line,lineno", OBJECT_LINES, ids=[f"L{n}" for _, n in OBJECT_LINES])
def test_render_object_line_renders_or_says_what_to_install(line, lineno, workspace):
    proc = subprocess.run(["bash", "-c", line], cwd=workspace, env=_env(), capture_output=True, text=True,
                          timeout=300)
    out = proc.stdout + proc.stderr
    if _mitsuba_works():
        _check_ran(f"README line {lineno} (Mitsuba available)", proc, out)
        stem = workspace / _words(line)[3]
        assert stem.with_suffix(".png").is_file() and stem.with_suffix(".exr").is_file()
    else:
        assert proc.returncode == 2, f"README line {lineno} without Mitsuba: exit {proc.returncode}, want 2:\n{out}"
        assert "Traceback" not in out, out
        lines = out.strip().splitlines()
        assert len(lines) == 1 and "install" in lines[0], f"want one line with the install command, got:\n{out}"
