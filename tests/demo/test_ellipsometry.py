"""The ellipsometry tour: epoxy on silicon (Cauchy fit) and hematite in two orientations."""


def test_demo_hook(tmp_path):
    """The worked examples: epoxy thickness and Cauchy parameters within 3σ of the truth; hematite
    ordinary/extraordinary constants within 5 median σ of Querry's."""
    from pathlib import Path

    from nmmm.demo.ellipsometry import demo

    s = demo(tmp_path)
    assert set(s) >= {"title", "figures", "tables", "text"}
    assert all(Path(f).exists() for f in s["figures"])
    assert all(abs(row["z"]) < 3 for row in s["tables"]["epoxy_fit"])
    h = s["tables"]["hematite"]
    assert max(h["max_dev_ordinary"], h["max_dev_extraordinary"]) < 6 * h["median_sigma_n"]
