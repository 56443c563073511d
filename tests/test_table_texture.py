"""The integrator's view of the diffuse tables: lookups land on the right level, channel,
direction and height, and the data the kernels read does not change their hash."""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.render.jit_haze import owned_floats
from seahaze.render.table_texture import Z_UPSAMPLE, TableTexture

N_Z, N_MU, N_PHI, LEVELS = 6, 10, 8, 3
SLOPE_MU, SLOPE_PHI, SLOPE_Z = 0.5, 0.2, 0.8  # per unit μ, radian and relative height


def _linear_tables() -> np.ndarray:
    """(n_z, n_mu, n_phi, 3L) tables linear in μ, folded azimuth and height at the bin
    centres, with an offset of their own per level and channel."""
    z = (np.arange(N_Z) + 0.5) / N_Z
    mu = -1.0 + 2.0 * (np.arange(N_MU) + 0.5) / N_MU
    phi = np.pi * (np.arange(N_PHI) + 0.5) / N_PHI
    field = (
        SLOPE_Z * z[:, None, None] + SLOPE_MU * mu[None, :, None] + SLOPE_PHI * phi[None, None, :]
    )
    offsets = 10.0 * np.arange(1, 3 * LEVELS + 1)  # level k, channel c: 10·(3k + c + 1)
    return (field[..., None] + offsets).astype(np.float32)


def _random_queries(n: int, sun_azimuth: float, seed: int = 5):
    """Travel directions and heights inside the bin centres, as numpy arrays: μ, folded
    azimuth φ, the direction (n, 3) and the relative height."""
    rng = np.random.default_rng(seed)
    mu = rng.uniform(-1.0 + 1.0 / N_MU, 1.0 - 1.0 / N_MU, n)
    phi = rng.uniform(np.pi / (2 * N_PHI), np.pi - np.pi / (2 * N_PHI), n)
    side = rng.choice([-1.0, 1.0], n)  # the table is folded: ±φ from the sun look the same
    azimuth = sun_azimuth + side * phi
    s = np.sqrt(1.0 - mu**2)
    travel = np.stack([s * np.cos(azimuth), s * np.sin(azimuth), mu], axis=1)
    return mu, phi, travel, rng.uniform(0.5 / N_Z, 1.0 - 0.5 / N_Z, n)


def test_lookups_average_to_bilinear_interpolation(mitsuba_variant) -> None:
    """Each lookup reads one texel, chosen with probability its bilinear weight: averaged over
    stratified picks, a linear field comes back as the field itself (to half a fine height bin
    in z and the picks' 1/N stratification), for every level and channel."""
    import drjit as dr
    import mitsuba as mi

    n, picks, sun_azimuth = 200, 512, 0.7
    mu, phi, travel, height = _random_queries(n, sun_azimuth)
    rep = lambda a: np.repeat(a, picks, axis=0)  # noqa: E731
    u = np.tile((np.arange(picks) + 0.5) / picks, n)
    texture = TableTexture(_linear_tables(), LEVELS)
    cos_sun, sin_sun = (dr.opaque(mi.Float, f(sun_azimuth)) for f in (np.cos, np.sin))
    d = rep(travel)
    lookup = texture.toward(mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]), cos_sun, sin_sun, mi.Float(u))
    field = SLOPE_MU * mu + SLOPE_PHI * phi + SLOPE_Z * height
    # A texel's value differs from its neighbour's by at most the slope × the bin width; a
    # stratified choice between two is off by at most 1/picks of it per axis.
    texel_step = SLOPE_MU * 2.0 / N_MU + SLOPE_PHI * np.pi / N_PHI
    tolerance = SLOPE_Z * 0.5 / (N_Z * Z_UPSAMPLE) + 2.0 * texel_step / picks + 1e-4
    for level in range(LEVELS):
        rgb = lookup(level, mi.Float(rep(height)))
        for c in range(3):
            mean = np.array(rgb[c]).reshape(n, picks).mean(axis=1)
            expected = field + 10.0 * (3 * level + c + 1)
            np.testing.assert_allclose(mean, expected, atol=tolerance)


def test_each_lookup_is_one_texel(mitsuba_variant) -> None:
    """A single lookup returns one of the four texels around the direction (not a blend), at
    the fine height bin of the query: the choice adds noise, never a value of its own."""
    import drjit as dr
    import mitsuba as mi

    n, sun_azimuth = 500, 0.7
    mu, phi, travel, height = _random_queries(n, sun_azimuth, seed=9)
    u = np.random.default_rng(2).random(n)
    texture = TableTexture(_linear_tables(), LEVELS)
    cos_sun, sin_sun = (dr.opaque(mi.Float, f(sun_azimuth)) for f in (np.cos, np.sin))
    d = mi.Vector3f(travel[:, 0], travel[:, 1], travel[:, 2])
    value = np.array(texture.toward(d, cos_sun, sin_sun, mi.Float(u))(0, mi.Float(height))[0])
    fine = texture.values.numpy().reshape(N_MU, N_PHI, N_Z * Z_UPSAMPLE, LEVELS, 4)
    i_mu = np.floor((mu + 1.0) * 0.5 * N_MU - 0.5).astype(int)
    i_phi = np.floor(phi / np.pi * N_PHI - 0.5).astype(int)
    i_z = np.floor(height * N_Z * Z_UPSAMPLE).astype(int)
    corners = np.stack(
        [fine[i_mu + a, i_phi + b, i_z, 0, 0] for a in (0, 1) for b in (0, 1)], axis=1
    )
    assert np.all(np.min(np.abs(corners - value[:, None]), axis=1) < 1e-5)


def test_an_unfolded_table_wraps_around_behind_the_sun(mitsuba_variant) -> None:
    """Unfolded (azimuth over the whole circle, the sun at the middle), the direction away from
    the sun lies between the last texel and the first: a lookup there picks each half the time,
    where a folded table clamps to its edge."""
    import drjit as dr
    import mitsuba as mi

    tables = _linear_tables()
    texture = TableTexture(tables, LEVELS, folded=False)
    sun_azimuth, picks = 0.3, 4096
    away = -np.array([np.cos(sun_azimuth), np.sin(sun_azimuth), 0.0])
    d = mi.Vector3f(*(np.full(picks, c, np.float32) for c in away))
    u = mi.Float((np.arange(picks) + 0.5) / picks)
    cos_sun, sin_sun = (dr.opaque(mi.Float, float(f(sun_azimuth))) for f in (np.cos, np.sin))
    value = np.array(texture.toward(d, cos_sun, sin_sun, u)(0, mi.Float(np.full(picks, 0.5)))[0])
    fine = texture.values.numpy().reshape(N_MU, N_PHI, N_Z * Z_UPSAMPLE, LEVELS, 4)
    i_mu, i_z = N_MU // 2 - 1, N_Z * Z_UPSAMPLE // 2  # μ = 0 lies between two bins
    first = fine[[i_mu, i_mu + 1], 0, i_z, 0, 0].mean()
    last = fine[[i_mu, i_mu + 1], N_PHI - 1, i_z, 0, 0].mean()
    assert value.mean() == pytest.approx(0.5 * (first + last), rel=1e-3)
    assert first != pytest.approx(last)


def test_lookup_clamps_at_the_table_edges(mitsuba_variant) -> None:
    """Beyond the outermost bin centres (straight up, the sun's own azimuth, the slab's top)
    a lookup holds the edge value, as a clamped texture does, whatever the pick."""
    import drjit as dr
    import mitsuba as mi

    tables = _linear_tables()
    texture = TableTexture(tables, LEVELS)
    up = mi.Vector3f(float(np.cos(0.3)) * 1e-4, float(np.sin(0.3)) * 1e-4, 1.0)  # at the sun's
    for u in (0.0, 0.3, 0.7, 0.99999):
        sun = (dr.opaque(mi.Float, float(f(0.3))) for f in (np.cos, np.sin))
        value = texture.toward(up, *sun, mi.Float(u))(1, mi.Float(1.0))
        np.testing.assert_allclose(np.array(value).ravel(), tables[-1, -1, 0, 3:6], rtol=1e-5)


@pytest.mark.parametrize("offset", [1, 2, 3])
def test_owned_arrays_keep_the_kernel_whatever_numpy_address(mitsuba_variant, offset) -> None:
    """A packet gather from :func:`owned_floats` compiles to the same kernel for data at any
    numpy address (a numpy-mapped source at an unaligned one got scalar gathers instead: a
    different kernel, compiled again for another scene)."""
    import drjit as dr
    import mitsuba as mi

    def kernel_hash(values: np.ndarray) -> tuple[str, np.ndarray]:
        source = owned_floats(values)
        index = dr.arange(mi.UInt32, 64) + dr.opaque(mi.UInt32, 1)
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()
        texel = dr.gather(mi.Vector4f, source, index)
        out = texel.x + 2.0 * texel.w
        dr.eval(out)
        history = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        return history[-1]["hash"], np.array(out)

    buffer = np.arange(4 * 1024 + 8, dtype=np.float32)
    aligned_hash, aligned = kernel_hash(buffer[: 4 * 1024])
    shifted_hash, shifted = kernel_hash(buffer[offset : offset + 4 * 1024])
    assert aligned_hash == shifted_hash
    # And the values are the data's: texel i holds elements 4i … 4i + 3.
    i = np.arange(64) + 1
    np.testing.assert_array_equal(aligned, 4 * i + 2 * (4 * i + 3))
    np.testing.assert_array_equal(shifted, aligned + 3 * offset)
