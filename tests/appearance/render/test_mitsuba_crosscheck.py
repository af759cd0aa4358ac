"""Issue 19 item 5: nmmm's plate renderer against Mitsuba 3 (an independent Monte-Carlo renderer)
with the ``nmmm_paint`` BSDF, region by region (3 x 3 regions of the plate), for the shipped solid
hematite recipe and the grey metallic recipe's statistical flake BRDF (no glints), under a point
lamp and a uniform D65 sky. Skipped without Mitsuba 3 / libLLVM >= 17."""

from pathlib import Path

import numpy as np
import pytest

from nmmm.appearance.render import PointLight, UniformEnvironment

EXAMPLES = Path(__file__).resolve().parents[3] / "src" / "nmmm" / "recipes" / "examples"
W = np.arange(400.0, 701.0, 20.0)


def _mitsuba():
    try:
        from nmmm.appearance.render.mitsuba_paint import require_mitsuba

        return require_mitsuba("llvm_ad_spectral")
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"Mitsuba unavailable: {exc}")


def _recipe_brdf(name):
    from nmmm.recipes.render_cli import plate_from_recipe_file

    plate, _ = plate_from_recipe_file(EXAMPLES / name)
    return plate.brdf  # the statistical BRDF (flakes averaged) for an effect paint


# ~9 s for the hematite (its sky light is sampled by Mitsuba), ~4 s for the metallic (kept in the quick run)
@pytest.mark.parametrize("recipe", [pytest.param("hematite_paint.toml", marks=pytest.mark.slow), "grey_metallic.toml"])
def test_plate_regions_match_mitsuba(recipe):
    _mitsuba()
    from nmmm.appearance.render.mitsuba_crosscheck import crosscheck_plate

    brdf = _recipe_brdf(recipe)
    lamp = PointLight((0.0, 150.0, 300.0), "D65", 1.0)
    sky = UniformEnvironment("D65", 0.1)
    cc = crosscheck_plate(brdf, [lamp], sky, position_mm=(0.0, -250.0, 300.0), fov_deg=35, resolution=(48, 32),
                          spp=1024, wavelength_nm=W, grid=(3, 3))
    print(cc.table())
    # Mitsuba's Monte-Carlo noise per region is well under the 2 % tolerance (measured 0.1-0.3 %)
    assert cc.standard_error.max() < 0.005, cc.table()
    assert cc.pixels.min() >= 20
    # mean radiance per region within 2 % (measured |dev| <= 0.6 %: D65's lines box-averaged per
    # 20 nm band by Mitsuba's film vs sampled at the grid by nmmm give -0.4 %)
    assert np.abs(cc.deviation).max() < 0.02, cc.table()
    # (band by band the plate means differ by up to 5-7 % at 400 nm: Mitsuba's film averages D65 over
    # the half band 400-410 nm where D65 rises by 10 %, nmmm samples it at 400 nm; not a test)
    print("band deviation %", np.round(100 * cc.band_deviation, 1))
    # the regions differ (gradient across the plate) and Mitsuba sees the same gradient
    assert np.ptp(cc.mean_nmmm) > 0.05 * cc.mean_nmmm.mean()
    assert np.corrcoef(cc.mean_mitsuba.ravel(), cc.mean_nmmm.ravel())[0, 1] > 0.99


def test_regions_refuse_a_plate_smaller_than_the_grid():
    from nmmm.appearance.render.mitsuba_crosscheck import plate_regions
    from nmmm.errors import InvalidInputError

    on = np.zeros((10, 10), bool)
    on[4:7, 4:7] = True
    with pytest.raises(InvalidInputError, match="fewer than"):
        plate_regions(on, (3, 3))
    regs = plate_regions(np.ones((12, 12), bool), (2, 2))
    assert len(regs) == 4 and sum(int(m.sum()) for _, _, m in regs) == 100


@pytest.mark.slow  # ~17 s
def test_booth_plate_regions_match_mitsuba():
    """The hematite recipe in the viewing booth (25 mm D65 lamp at 45 deg behind the plate, grey walls
    as nmmm's lat-long map -> Mitsuba's nmmm_envmap, spherical area lamp): the coat's mirror image of
    the lit back wall and the lamp's fall-off agree region by region (measured |dev| <= 0.4 %,
    s.e. <= 0.3 %). This caught nmmm_envmap reading the map turned by 180 deg in azimuth."""
    _mitsuba()
    from nmmm.appearance.render import PaintedPlate, ViewingBooth
    from nmmm.appearance.render.mitsuba_crosscheck import crosscheck_plate

    brdf = _recipe_brdf("hematite_paint.toml")
    scene = ViewingBooth(source="45").scene(PaintedPlate(brdf), W)
    cc = crosscheck_plate(brdf, scene["lights"], scene["environment"], position_mm=(0.0, -333.0, 222.0),
                          fov_deg=40, resolution=(48, 32), spp=4096, wavelength_nm=W)
    print(cc.table())
    assert cc.standard_error.max() < 0.005, cc.table()
    assert np.abs(cc.deviation).max() < 0.02, cc.table()
    # the back wall's mirror image makes the near (bottom) middle region 2.7x the far corners
    assert cc.mean_mitsuba[2, 1] > 2 * cc.mean_mitsuba[0, 0]


def _booth_point_lamp(brdf):
    """The 45-degree booth's source as a point lamp (radius 0) for both renderers: nmmm shades a lamp of
    any radius as a point (PointLight's docstring), so this is the scene as nmmm models it; the 25 mm
    sphere's mirror image does not fall on the plate from this camera."""
    import dataclasses

    from nmmm.appearance.render import PaintedPlate, ViewingBooth

    scene = ViewingBooth(source="45").scene(PaintedPlate(brdf), W)
    return [dataclasses.replace(lt, radius_mm=0.0) for lt in scene["lights"]], scene["environment"]


@pytest.mark.slow
def test_booth_lamp_on_the_metallic_matches_mitsuba():
    """The grey metallic recipe (statistical flakes) lit by the booth's 45-degree D65 lamp as a point lamp
    in both renderers: region means within 2 % (measured |dev| <= 0.64 %, s.e. <= 0.13 % at 4096 spp;
    with Mitsuba's 25 mm sphere instead, -1.9 % at the flake highlight (-2.5 % before ae0fc01): nmmm shades
    it as a point)."""
    _mitsuba()
    from nmmm.appearance.render.mitsuba_crosscheck import crosscheck_plate

    brdf = _recipe_brdf("grey_metallic.toml")
    lamps, _ = _booth_point_lamp(brdf)
    cc = crosscheck_plate(brdf, lamps, None, position_mm=(0.0, -333.0, 222.0), fov_deg=40, resolution=(48, 32),
                          spp=4096, wavelength_nm=W)
    print(cc.table())
    assert cc.standard_error.max() < 0.005, cc.table()
    assert np.abs(cc.deviation).max() < 0.02, cc.table()
    assert np.ptp(cc.mean_nmmm) > 0.5 * cc.mean_nmmm.mean()  # the flake highlight in the middle column


@pytest.mark.slow
def test_booth_metallic_with_walls_matches_mitsuba():
    """The grey metallic recipe in the whole booth (point lamp as above + the grey walls as a lat-long map):
    the issue's 'same scene (plate, source, booth)' for a metallic paint. With the renderer's hemisphere
    quadrature at 8 x 16 cells this was +2.8 to +3.2 % in the middle column (the walls' light on the flake
    lobe 12-15 % low); at 16 x 32 cells every region is within 1.3 % (4096 spp, s.e. <= 0.4 %)."""
    _mitsuba()
    from nmmm.appearance.render.mitsuba_crosscheck import crosscheck_plate

    brdf = _recipe_brdf("grey_metallic.toml")
    lamps, env = _booth_point_lamp(brdf)
    cc = crosscheck_plate(brdf, lamps, env, position_mm=(0.0, -333.0, 222.0), fov_deg=40, resolution=(48, 32),
                          spp=4096, wavelength_nm=W)
    print(cc.table())
    assert cc.standard_error[:, 1].max() < 0.01, cc.table()
    assert np.abs(cc.deviation).max() < 0.02, cc.table()
