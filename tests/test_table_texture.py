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


def test_lookup_interpolates_a_linear_table_exactly(mitsuba_variant) -> None:
    """Linear interpolation reproduces a linear field: inside the bin centres every lookup is
    the field itself, to half a fine height bin in z, for every level and channel."""
    import drjit as dr
    import mitsuba as mi

    rng = np.random.default_rng(5)
    n = 3000
    sun_azimuth = 0.7
    mu = rng.uniform(-1.0 + 1.0 / N_MU, 1.0 - 1.0 / N_MU, n)
    phi = rng.uniform(np.pi / (2 * N_PHI), np.pi - np.pi / (2 * N_PHI), n)
    side = rng.choice([-1.0, 1.0], n)  # the table is folded: ±φ from the sun look the same
    azimuth = sun_azimuth + side * phi
    s = np.sqrt(1.0 - mu**2)
    travel = mi.Vector3f(s * np.cos(azimuth), s * np.sin(azimuth), mu)
    height = rng.uniform(0.5 / N_Z, 1.0 - 0.5 / N_Z, n)

    texture = TableTexture(_linear_tables(), LEVELS)
    cos_sun, sin_sun = (dr.opaque(mi.Float, f(sun_azimuth)) for f in (np.cos, np.sin))
    lookup = texture.toward(travel, cos_sun, sin_sun)
    field = SLOPE_MU * mu + SLOPE_PHI * phi + SLOPE_Z * height
    z_step = SLOPE_Z * 0.5 / (N_Z * Z_UPSAMPLE)
    for level in range(LEVELS):
        rgb = lookup(level, mi.Float(height))
        for c in range(3):
            expected = field + 10.0 * (3 * level + c + 1)
            np.testing.assert_allclose(np.array(rgb[c]), expected, atol=z_step + 1e-4)


def test_lookup_clamps_at_the_table_edges(mitsuba_variant) -> None:
    """Beyond the outermost bin centres (straight up, the sun's own azimuth, the slab's top)
    a lookup holds the edge value, as a clamped texture does."""
    import drjit as dr
    import mitsuba as mi

    tables = _linear_tables()
    texture = TableTexture(tables, LEVELS)
    up = mi.Vector3f(float(np.cos(0.3)) * 1e-4, float(np.sin(0.3)) * 1e-4, 1.0)  # at the sun's
    sun = (dr.opaque(mi.Float, float(f(0.3))) for f in (np.cos, np.sin))
    value = texture.toward(up, *sun)(1, mi.Float(1.0))
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
