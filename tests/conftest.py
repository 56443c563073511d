"""Shared fixtures: tiny scenes built straight from numpy, so render tests need no ocean or
vessel library and every expected value can be computed analytically."""

from __future__ import annotations

import contextlib
import io
import signal
import time
from collections.abc import Iterator

import numpy as np
import pytest

from seahaze.camera import Camera
from seahaze.spec import SceneSpec
from seahaze.world import MeshData, SceneGeometry, VesselInstance

PLANE_HALF_SIZE_M = 2.0e5


def region_stats(images: list[np.ndarray], *masks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-region mean RGB, (regions, 3), of each of ``images`` (one per seed), averaged over
    the images, and its standard error (their spread over sqrt of their count)."""
    means = np.array([[image[mask].mean(axis=0) for mask in masks] for image in images])
    return means.mean(axis=0), means.std(axis=0, ddof=1) / np.sqrt(len(images))


class SkyAndSea:
    """One small scene built twice from ``geometry`` — with Mitsuba's medium (``reference``)
    and without (``physical``) — through ``medium`` (default: the spec's haze), and the sky and
    sea means of the level of visibility ``visibility`` in either mode."""

    def __init__(self, spec: SceneSpec, geometry: SceneGeometry, visibility: float, medium=None):
        from seahaze.render import passes
        from seahaze.render.scene import build_scene
        from seahaze.visibility import channel_extinction

        self.spec = spec
        camera = Camera.from_spec(spec.camera)
        self.scenes = {
            mode: build_scene(
                spec, camera, geometry, [visibility], haze_box=mode == "reference", medium=medium
            )
            for mode in ("reference", "physical")
        }
        self.geo = passes.render_geometry(self.scenes["physical"])
        self.clean = passes.render_clean(self.scenes["physical"], 16, 1, 0.998, 0.75)
        self.sky = np.isinf(self.geo.distance_m)
        self.sea = ~self.sky & (self.geo.instance < 0)
        self.sigma = channel_extinction(visibility, "koschmieder", "grey")

    def means(self, mode: str, spp: int, loaded=None) -> tuple[np.ndarray, np.ndarray]:
        """Sky and sea means per channel, (2, 3), and their standard errors over 4 seeds, of
        ``mode``'s scene (or ``loaded``)."""
        from seahaze.render.levels import LevelRenderer

        spec = self.spec
        loaded = loaded or self.scenes[mode]
        renderer = LevelRenderer(mode, loaded, self.geo, self.clean, spec.haze, spec.render)
        images = [
            renderer.render(
                self.sigma, 0, spec.render.model_copy(update={"spp": spp, "seed": s})
            ).radiance
            for s in range(4)
        ]
        return region_stats(images, self.sky, self.sea)


@pytest.fixture(autouse=True)
def seahaze_state(tmp_path_factory, monkeypatch):
    """seahaze's state folder (the digests of the records of files it wrote into users'
    folders) per test, not the home's: a test sees only the records it wrote itself."""
    from seahaze.dataset.owned import STATE_ENV

    monkeypatch.setenv(STATE_ENV, str(tmp_path_factory.mktemp("state")))


def emitter_radiance(emitter, direction) -> np.ndarray:
    """The radiance (linear RGB) a loaded Mitsuba ``emitter`` sends back along the unit world
    ``direction`` (the direction one looks in to see it)."""
    import drjit as dr
    import mitsuba as mi

    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*[float(-x) for x in direction])
    return np.array(emitter.eval(si)).ravel()


def flat_sea_mesh(rings: int = 96, sectors: int = 128) -> MeshData:
    """The sea as a flat camera-centred polar grid at z = 0.

    Ring radii grow geometrically from 0.5 m to PLANE_HALF_SIZE_M so that triangles stay small
    relative to their distance: float32 hit points on one huge triangle are off by centimetres.
    """
    radii = np.geomspace(0.5, PLANE_HALF_SIZE_M, rings)
    angles = np.linspace(0.0, 2.0 * np.pi, sectors, endpoint=False)
    ring_xy = np.stack(
        [np.outer(radii, np.cos(angles)), np.outer(radii, np.sin(angles))], axis=-1
    ).reshape(-1, 2)
    vertices = np.vstack(
        [[0.0, 0.0, 0.0], np.column_stack([ring_xy, np.zeros(len(ring_xy))])]
    ).astype(np.float32)
    faces = [[0, 1 + s, 1 + (s + 1) % sectors] for s in range(sectors)]
    for r in range(rings - 1):
        for s in range(sectors):
            a, b = 1 + r * sectors + s, 1 + r * sectors + (s + 1) % sectors
            faces += [[a, a + sectors, b], [b, a + sectors, b + sectors]]
    return MeshData("sea", vertices, np.array(faces, np.uint32))


def box_vessel(
    index: int, center: tuple[float, float, float], size: tuple[float, float, float]
) -> VesselInstance:
    """An axis-aligned box standing in for a vessel (class id 0)."""
    import trimesh

    box = trimesh.creation.box(size)
    box.apply_translation(center)
    part = MeshData(
        f"vessel{index:03d}_hull",
        box.vertices.astype(np.float32),
        box.faces.astype(np.uint32),
        (0.3, 0.1, 0.1),
        0.4,
    )
    return VesselInstance(index, "box", 0, None, size[0], size[1], size[2], 0.0, [part])


def sun_and_sky_photons(count: int, seed: int, elevation_deg: float = 35.0) -> tuple[tuple, tuple]:
    """Source photons for the diffuse-field tracers: a sun at ``elevation_deg`` whose light
    travels toward azimuth 216.87° (counted from +x toward +y), irradiance 1 W m⁻² on a
    horizontal plane, and a uniform sky of the same horizontal irradiance, ``count`` photons
    each, travelling down."""
    rng = np.random.default_rng(seed)
    elevation = np.radians(elevation_deg)
    sun_d = np.tile([-np.cos(elevation) * 0.8, -np.cos(elevation) * 0.6, 0.0], (count, 1))
    sun_d[:, 2] = -np.sin(elevation)
    sun = (sun_d, np.full((count, 3), 1.0 / count))
    mu = np.sqrt(rng.random(count))  # cosine-weighted: each photon carries equal irradiance
    phi = 2.0 * np.pi * rng.random(count)
    s = np.sqrt(1.0 - mu**2)
    sky_d = np.stack([s * np.cos(phi), s * np.sin(phi), -mu], axis=1)
    return sun, (sky_d, np.full((count, 3), 1.0 / count))


def eight_way_sea():
    """A sea that sends every photon up at one of eight fixed directions with weight 0.3
    (a ``SeaReflectance``; import it once a Mitsuba variant is set)."""
    from seahaze.render.photon_tracer import SeaReflectance

    up = np.radians([10.0, 20.0, 35.0, 50.0, 60.0, 70.0, 80.0, 89.0])
    wo = np.stack([np.cos(up), np.zeros_like(up), np.sin(up)], axis=1)
    return SeaReflectance(wo[None], np.full((1, len(up), 3), 0.3))


def assert_same_plane_parallel_field(got: np.ndarray, want: np.ndarray, n_mu: int) -> None:
    """Two directional fluences ``[z, dir, channel]`` (R, G, B, or one of luminance) of the
    same plane-parallel haze from two tracers (their own photon noise): every height's four
    bands of ``μ`` (summed over azimuth) hold light and agree within 3 %, the totals within
    0.5 %."""

    def bands(fluence: np.ndarray) -> np.ndarray:
        n_z, channels = fluence.shape[0], fluence.shape[-1]
        by_mu = fluence.reshape(n_z, n_mu, -1, channels).sum(axis=2)
        return by_mu.reshape(n_z, 4, n_mu // 4, channels).sum(axis=2)

    assert np.all(bands(want) > 0.0)
    np.testing.assert_allclose(bands(got), bands(want), rtol=0.03)
    np.testing.assert_allclose(got.sum(), want.sum(), rtol=0.005)


def small_spec(**sections) -> SceneSpec:
    """A SceneSpec with a tiny default resolution, overridden by ``sections``."""
    data = {"camera": {"resolution": [64, 36]}, "render": {"spp": 4}}
    for key, value in sections.items():
        data.setdefault(key, {}).update(value)
    return SceneSpec.model_validate(data)


@pytest.fixture(scope="session")
def mitsuba_variant() -> str:
    from seahaze.render.variant import select_variant

    return select_variant("auto")


def load_flat_scene(
    spec: SceneSpec, vessels=(), visibilities=(1000.0,), haze_box=True, sea_roughness=0.05
):
    """Load a Mitsuba scene with a flat sea and the given box vessels (``haze_box=False`` for
    the physical mode)."""
    from seahaze.render.scene import build_scene

    camera = Camera.from_spec(spec.camera)
    geometry = SceneGeometry(flat_sea_mesh(), sea_roughness, None, list(vessels))
    return build_scene(spec, camera, geometry, list(visibilities), haze_box=haze_box), camera


@pytest.fixture(scope="session")
def dataset(tmp_path_factory):
    """The default scene rendered once by the CLI at 64×36, 2 spp, levels 300 and 4000 m, with
    ``--split none``: the dataset without a split (train = val = every clean image) that the
    tests of that layout read (one scene is too few for a split anyway)."""
    from pathlib import Path

    from seahaze.cli import main

    out = tmp_path_factory.mktemp("ds")
    scene = Path(__file__).resolve().parents[1] / "scenes" / "default.yaml"
    args = [
        "render",
        str(scene),
        "--vis",
        "300,4000",
        "--res",
        "64x36",
        "--spp",
        "2",
        "--out",
        str(out),
        "--split",
        "none",
        "--quiet",
    ]
    assert main(args) == 0
    return out


SPLIT_TEMPLATE = """\
name: tiny
camera: {height_m: 12, pitch_deg: -2, resolution: [64, 36]}
sun: {elevation_deg: 30, azimuth_deg: 140}
sea: {quality: low, seed: 99}
vessels:
  sample: {count: 3, distance_m: [120, 900], seed: 5}
haze: {levels: [500, 2000]}
render: {spp: 1, airlight_spp: 16, seed: 3}
variation:
  camera_heading_deg: [-30, 30]
"""
SPLIT_SCENES = 6
SPLIT_FRACTIONS = "0.5,0.25,0.25"


@pytest.fixture(scope="session")
def split_template(tmp_path_factory):
    """A tiny scene file (64×36 px, 1 spp, levels 500 and 2000 m) for split and export tests."""
    path = tmp_path_factory.mktemp("split_scene") / "tiny.yaml"
    path.write_text(SPLIT_TEMPLATE)
    return path


@pytest.fixture(scope="session")
def split_dataset(split_template, tmp_path_factory):
    """SPLIT_SCENES scenes of the tiny template rendered with --split 0.5,0.25,0.25 (read-only:
    copy it before changing it)."""
    from seahaze.cli import main

    out = tmp_path_factory.mktemp("split_ds")
    args = ["render", str(split_template), "--scenes", str(SPLIT_SCENES), "--split"]
    assert main([*args, SPLIT_FRACTIONS, "--out", str(out), "--quiet"]) == 0
    return out


CASE_SECONDS = 10
"""How long one hostile-input case may run in this process before it fails as a hang."""


@contextlib.contextmanager
def deadline(seconds: int = CASE_SECONDS) -> Iterator[None]:
    """Fail (instead of hanging the suite) when a case runs longer than ``seconds``."""

    def expired(_signum, _frame):
        raise TimeoutError(f"case ran longer than {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    start = time.perf_counter()
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert time.perf_counter() - start < seconds


def cli_run(args: list[str], seconds: int = CASE_SECONDS) -> tuple[int, str, str]:
    """``seahaze ARGS`` in this process within ``seconds``: exit code (argparse's SystemExit
    too), stdout, stderr. Any other exception is a traceback the user would see: it fails the
    test."""
    from seahaze.cli import main

    out, err = io.StringIO(), io.StringIO()
    with deadline(seconds), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return code, out.getvalue(), err.getvalue()


TINY_SEQUENCE = """\
name: tinyseq
camera: {height_m: 12, pitch_deg: -2, fov_deg: 40, resolution: [64, 36]}
sun: {elevation_deg: 30, azimuth_deg: 140}
sea: {quality: low, seed: 99, wind_speed: 8}
vessels:
  follow_slope: true
  placed:
    - {class: passenger_ferry, distance_m: 260, bearing_deg: 3, heading_deg: 175, length_m: 60,
       speed_kn: 20}
    - {class: tug, distance_m: 150, bearing_deg: -10, heading_deg: 60, length_m: 25,
       speed_kn: 10, turn_rate_deg_s: 2}
haze: {levels: [1000]}
sequence: {frames: 3, fps: 2}
render: {spp: 1, seed: 3}
"""
"""A 3-frame sequence of two moving vessels at 64×36, 1 spp: the sequence tests' scene."""


PAIR_SCENE = """\
name: pair
camera: {height_m: 15, fov_deg: 20, pitch_deg: -3, resolution: [64, 36]}
sea: {quality: low, seed: 3}
vessels:
  placed:
    - {class: fishing_boat, distance_m: 150, bearing_deg: 4, heading_deg: 90, length_m: 18}
    - {class: container_ship, distance_m: 2000, bearing_deg: -4, heading_deg: 90, length_m: 200}
haze: {levels: [300, 4000]}
labels: {write_visible: WRITE}
render: {spp: 4, seed: 1, write_exr: false}
"""
"""Two vessels whose visibility at 300 m is known: the boat at 150 m is seen, the ship 2 km away
is not (at 4000 m both are). ``WRITE``: ``true`` or ``false`` for ``labels.write_visible``."""


def assert_parts_within_reported_size(model, seed) -> None:
    """Every part of a built vessel ``model`` lies inside the length, beam (2 cm for fenders
    and rubbing strakes) and air draft it reports."""
    for part in model.parts:
        (x0, y0, _), (x1, y1, z1) = part.mesh.bounds
        assert -0.5 * model.length_m - 1e-6 <= x0 and x1 <= 0.5 * model.length_m + 1e-6
        assert max(abs(y0), abs(y1)) <= 0.5 * model.beam_m + 0.02, (seed, part.name)
        assert z1 <= model.air_draft_m
