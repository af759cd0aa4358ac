"""A sub-command whose module cannot be imported is listed as unavailable and says why, in the CLI's one
voice, instead of crashing with a NameError (the reason was read after the except block had unbound it)."""

from nmmm import cli as nmmm_cli


def test_unavailable_command_says_why(monkeypatch, capsys):
    monkeypatch.setitem(nmmm_cli.COMMANDS, "broken", ("nmmm.no_such_module:cli", "A command that cannot load."))
    status = nmmm_cli.main(["broken"])
    err = capsys.readouterr().err
    assert status != 0
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "'nmmm broken' is not available" in lines[0] and "no_such_module" in lines[0]
    assert "Traceback" not in err and "NameError" not in err
