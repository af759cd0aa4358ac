"""``nmmm render`` speaks with the CLI's one voice: a data error is one ``error:`` line on stderr and
exit status 2 (not click's 'Error:' and exit 1); a render over --max-memory-gb is refused naming it."""

from click.testing import CliRunner

from nmmm.appearance.render.cli import render
from nmmm.cli import main


def test_data_error_is_one_error_line_exit_2(tmp_path, capsys):
    assert main(["render", "plate", str(tmp_path / "x"), "--light", str(tmp_path / "none.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "not found" in err[0]
    # the render group alone (as registered by nmmm.recipes.render_cli) says the same
    res = CliRunner().invoke(render, ["plate", str(tmp_path / "y"), "--look-at-mm", "0", "0", "900",
                                      "--camera-mm", "0", "0", "400"])
    assert res.exit_code == 2 and res.output.startswith("error: ")


def test_max_memory_gb_refuses_a_large_render_naming_the_option(tmp_path, capsys):
    args = ["render", "plate", str(tmp_path / "p"), "--width", "40", "--height", "30", "--cells", "20", "15"]
    assert main(args + ["--max-memory-gb", "1e-9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "--max-memory-gb" in err[0]
    assert "render_plate(" not in err[0]
    assert main(args + ["--max-memory-gb", "0"]) == 2  # not a limit
    capsys.readouterr()
    assert main(args + ["--max-memory-gb", "4"]) == 0
    assert (tmp_path / "p.png").exists()
