"""``nmmm run`` prints a warning as one ``warning:`` line (not Python's path, line number and source
line), and Stack's coherent-layer advice names the recipe key that makes the layer incoherent."""

import warnings

from nmmm.cli import main
from nmmm.recipes.schema import example_path


def test_run_warning_is_one_line_naming_the_recipe_key(tmp_path, capsys):
    p = tmp_path / "thick.toml"
    p.write_text(example_path("interference_pigment").read_text().replace("step_nm = 5", "step_nm = 20"))
    args = ["run", str(p), "-o", str(tmp_path / "out"), "--no-progress", "--set", "thin_film.layers[0].coherent=true"]
    before = warnings.showwarning
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # tests/recipes/conftest.py quiets warnings by default
        assert main(args) == 0
    assert warnings.showwarning is before  # the command line's hook is restored when it ends
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    coherent = [ln for ln in err if "is coherent but" in ln]
    assert len(coherent) == 1, err
    assert coherent[0].startswith("warning: layer 0 ") and "thin_film.layers[0].coherent = false" in coherent[0]
    assert "Layer(material" not in coherent[0] and "UserWarning" not in "\n".join(err)
    assert not any(ln.startswith("  ") or ".py:" in ln for ln in err), err  # no source line, no file path


def test_library_warning_keeps_stack_terms_outside_a_recipe():
    import numpy as np
    import pytest

    from nmmm.layers import Stack

    with pytest.warns(UserWarning, match=r"coherent=False"):
        Stack([(1.5, 1e6)], substrate=1.5).rt(np.arange(400.0, 701.0, 10.0))
