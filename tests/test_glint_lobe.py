"""The sun glint's lobe (seahaze.render.glint_lobe) against independent computations.

* The mirror image of the sun, and no lobe when the sun is below the horizon.
* ``κ = 1/(2σ²)`` against Cox & Munk's published slope variance, and against the spread of sun
  rays reflected off facets whose slopes are drawn from Cox & Munk's Gaussian (an independent
  numpy reflection, no small-angle formula).
* The sampler and the density agree with Fisher's (1953) closed-form cap probability
  ``P(m·ω > c) = (1 − e^{−κ(1−c)}) / (1 − e^{−2κ})``, and the density integrates to one.
"""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.render import glint_lobe
from seahaze.world import sun_direction

pytestmark = pytest.mark.usefixtures("mitsuba_variant")


def test_the_mirror_image_is_the_sun_reflected_in_the_sea_plane() -> None:
    sun = sun_direction(28.0, 150.0)
    m = glint_lobe.mirror_axis(sun)
    e, a = np.radians(28.0), np.radians(150.0)
    np.testing.assert_allclose(m, [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), -np.sin(e)])
    assert glint_lobe.lobe_share(sun, 0.7) == 0.7
    assert glint_lobe.lobe_share(sun_direction(-3.0, 150.0), 0.7) == 0.0
    assert glint_lobe.lobe_share(sun, 0.7, shining=False) == 0.0


def test_kappa_follows_cox_munk() -> None:
    # Cox & Munk (1954): sigma² = 0.003 + 5.12e-3 U; at 7 m/s 0.03884, so kappa = 12.87.
    assert glint_lobe.lobe_kappa(7.0) == pytest.approx(1.0 / (2.0 * 0.03884), rel=1e-6)
    assert glint_lobe.lobe_kappa(0.0) == pytest.approx(1.0 / 0.006)
    assert glint_lobe.lobe_kappa(15.0) < glint_lobe.lobe_kappa(7.0) < glint_lobe.lobe_kappa(2.0)


@pytest.mark.parametrize("wind", [2.0, 7.0, 15.0])
def test_kappa_matches_the_spread_of_sun_rays_reflected_off_cox_munk_facets(wind: float) -> None:
    # Sun at the zenith: the glint is around the nadir. Facet slopes Gaussian, variance sigma²/2
    # per axis; reflect the downward sun ray off each facet and measure the angular variance of
    # the reflected direction per axis, which a von Mises-Fisher lobe has as 1/kappa.
    rng = np.random.default_rng(5)
    sigma2 = 0.003 + 5.12e-3 * wind
    slopes = rng.normal(0.0, np.sqrt(sigma2 / 2.0), size=(200_000, 2))
    normals = np.column_stack([-slopes, np.ones(len(slopes))])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    incoming = np.array([0.0, 0.0, -1.0])
    reflected = incoming - 2.0 * (normals @ incoming)[:, None] * normals
    up = reflected[reflected[:, 2] > 0.0]
    angles = np.arctan2(up[:, :2], up[:, 2:3])  # per-axis angle from the zenith
    per_axis = float(np.mean(np.var(angles, axis=0)))
    assert 1.0 / glint_lobe.lobe_kappa(wind) == pytest.approx(per_axis, rel=0.1)


@pytest.mark.parametrize("kappa", [4.0, 12.9, 60.0])
def test_samples_and_density_agree_with_fishers_closed_form(kappa: float) -> None:
    import mitsuba as mi

    n = 400_000
    m = glint_lobe.mirror_axis(sun_direction(28.0, 150.0))
    axis = mi.Vector3f(*(float(c) for c in m))
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(2, n)
    d = glint_lobe.lobe_sample(axis, kappa, sampler.next_2d())
    cos_to_axis = np.array(d).T @ m
    uniform = mi.warp.square_to_uniform_sphere(sampler.next_2d())
    density = np.array(glint_lobe.lobe_pdf(axis, kappa, uniform), np.float64)
    cos_uniform = np.array(uniform).T @ m
    # The density integrates to one over the sphere (uniform samples, pdf 1/4π).
    assert np.mean(density) * 4.0 * np.pi == pytest.approx(1.0, abs=0.02)
    for c in (0.99, 0.95, 0.8, 0.5):
        fisher = (1.0 - np.exp(-kappa * (1.0 - c))) / (1.0 - np.exp(-2.0 * kappa))
        assert np.mean(cos_to_axis > c) == pytest.approx(fisher, abs=3e-3)
        # The density's own integral over the cap, estimated from uniform directions.
        cap = np.mean(density * (cos_uniform > c)) * 4.0 * np.pi
        assert cap == pytest.approx(fisher, abs=0.02)


@pytest.mark.usefixtures("mitsuba_variant")
def test_the_lobe_serves_the_side_a_path_arrives_on_and_a_translucent_sheet_from_both() -> None:
    """A vertical surface facing the sun's mirror image (normal toward it) draws toward the
    lobe when the path arrives on its normal's side; met from behind (a sheet seen from its
    other face, its normal away from the path) the same opaque surface faces away and does
    not, while the same surface seen from the far side with its normal turned round does. A
    translucent sheet can send the path through itself: it draws from either side."""
    import drjit as dr
    import mitsuba as mi

    from seahaze.render.fleet import vessel_bsdf

    sun = sun_direction(20.0, 0.0)
    lobe = glint_lobe.GlintLobe(sun, wind_speed=6.0, share=0.7)
    paint = {"type": "rgb", "value": [0.8, 0.8, 0.8]}
    opaque = mi.load_dict(vessel_bsdf(0.4, paint))
    cloth = mi.load_dict(vessel_bsdf(0.85, paint, 0.3))
    axis = glint_lobe.mirror_axis(sun)
    toward = np.array([axis[0], axis[1], 0.0]) / np.hypot(axis[0], axis[1])

    def share(bsdf, normal_sign: float, arrive_from_normal_side: bool) -> float:
        si = dr.zeros(mi.SurfaceInteraction3f, 1)
        n = normal_sign * toward
        si.n = mi.Normal3f(*(float(c) for c in n))
        si.sh_frame = mi.Frame3f(si.n)
        si.wi = mi.Vector3f(0.3, 0.0, 0.95 if arrive_from_normal_side else -0.95)
        return float(lobe.share_at(si, bsdf, mi.Bool(True))[0])

    assert share(opaque, 1.0, True) == pytest.approx(0.7)  # its lit side faces the lobe
    assert share(opaque, 1.0, False) == 0.0  # met from behind: the side seen faces away
    assert share(opaque, -1.0, False) == pytest.approx(0.7)  # seen from the lobe's side
    assert share(opaque, -1.0, True) == 0.0
    for normal_sign in (1.0, -1.0):
        for arrive in (True, False):
            assert share(cloth, normal_sign, arrive) == pytest.approx(0.7)
