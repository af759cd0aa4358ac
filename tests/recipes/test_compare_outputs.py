"""A comparison's output folder holds only that comparison (review of issue 25 item 5)."""

from nmmm.recipes.compare import MAX_FOLDER_NAME, compare_recipes, recipe_folders
from nmmm.recipes.schema import set_key

from .conftest import fast_raw


def test_second_compare_into_one_folder_leaves_only_its_runs_and_user_files(tmp_path):
    a = set_key(fast_raw("hematite_paint", step_nm=40.0), "name", "Old one")
    b = set_key(a, "name", "Old two")
    out = tmp_path / "cmp"
    compare_recipes(a, b, out, illuminants=["D65"], progress=False)
    assert (out / "Old_one").is_dir() and (out / "Old_two").is_dir()
    (out / "my_notes.txt").write_text("mine")
    (out / "my_folder").mkdir()
    (out / "my_folder" / "x.csv").write_text("1\n")
    c = set_key(a, "name", "New " + "x" * 300)  # a name too long for a folder name as it is
    d = set_key(a, "name", "New " + "x" * 299 + "y")
    res = compare_recipes(c, d, out, illuminants=["D65"], progress=False)
    runs = sorted(p.name for p in out.iterdir() if p.is_dir())
    assert runs == sorted(["my_folder"] + [p.split("/")[-1] for p in res["folders"]])
    assert all(len(p.split("/")[-1]) <= MAX_FOLDER_NAME for p in res["folders"])
    assert (out / "my_notes.txt").read_text() == "mine" and (out / "my_folder" / "x.csv").exists()
    assert not (out / ".Old_one.nmmm-lock").exists()
    assert (out / "report.html").exists() and (out / "spectra_overlay.png").exists()


def test_long_recipe_names_make_short_distinct_folders():
    fa, fb = recipe_folders("A" * 300, "A" * 299 + "B")
    assert len(fa) <= MAX_FOLDER_NAME and len(fb) <= MAX_FOLDER_NAME and fa != fb
    assert recipe_folders("Hematite paint (7 %)", "Other") == ("Hematite_paint_7", "Other")
    assert recipe_folders("x" * 300, "x" * 300)[0].endswith("_first")
