"""The rendering demo: the grey metallic plate, mono and stereo."""

import numpy as np
import pytest


@pytest.mark.slow
def test_demo_hook(tmp_path):
    from nmmm.demo.rendering import demo

    r = demo(tmp_path)
    assert all((tmp_path / f.split("/")[-1]).exists() for f in r["figures"])
    assert r["tables"]["render"]["shared_glint_fraction"] < 0.3
    assert np.isfinite(r["tables"]["render"]["seconds"])
