"""The clean image does not depend on the haze settings or the mode (issue #19).

In ``reference`` and ``asm`` the clean pass used to be rendered through the scene with the empty
haze box, whose null surfaces draw random numbers: its noise changed with ``haze.top_m``, the
levels (the box width) and whether the camera is inside the layer. It now renders a scene
without the box, so the clean image is bit-identical in every mode and for any haze.
"""

from __future__ import annotations

import numpy as np
import pytest

from seahaze.camera import Camera
from seahaze.spec import SceneSpec, with_changes
from seahaze.world import build_geometry

BASE = SceneSpec.model_validate(
    {
        "camera": {"height_m": 40.0, "pitch_deg": -3.0, "resolution": [32, 18]},
        "sea": {"quality": "low", "seed": 1},
        "vessels": {"placed": [{"class": "tug", "distance_m": 300, "length_m": 30}]},
        "haze": {"levels": [1000.0]},
        "render": {"spp": 2, "seed": 5},
    }
)
CASES = [
    ("reference", {"top_m": 1.0}),  # camera above a thin layer
    ("reference", {"top_m": 2000.0, "extinction_spectrum": "kim"}),  # camera inside the layer
    ("asm", {"levels": [50.0]}),  # a narrow box
    ("asm", {"levels": [4000.0, 100000.0], "albedo": 0.3, "g": -0.5, "threshold": "mor"}),
]


@pytest.fixture(scope="module")
def geometry(mitsuba_variant):
    return build_geometry(BASE, Camera.from_spec(BASE.camera))


def _clean(spec: SceneSpec, geometry) -> np.ndarray:
    from seahaze.render.engine import open_session

    return open_session(spec, geometry).render_clean()


@pytest.mark.slow
def test_clean_is_the_same_for_any_haze_in_every_mode(geometry):
    """Within a mode the clean image does not depend on the haze settings, to the byte. (The
    modes' clean images are different estimators of the same image: ``reference`` and ``asm``
    render it with Mitsuba's path tracer, ``physical`` with its own integrator, which samples
    sun and sky apart.)"""
    for mode, haze in [*CASES, ("physical", {"top_m": 1.0, "levels": [50.0, 4000.0]})]:
        expected = _clean(with_changes(BASE, {"render": {"mode": mode}}), geometry)
        assert np.isfinite(expected).all() and expected.mean() > 0
        spec = with_changes(BASE, {"render": {"mode": mode}, "haze": haze})
        assert np.array_equal(_clean(spec, geometry), expected), (mode, haze)


def test_the_haze_box_still_hazes_the_levels(geometry):
    from seahaze.render.engine import open_session
    from seahaze.visibility import channel_extinction

    spec = with_changes(BASE, {"render": {"mode": "reference"}})
    session = open_session(spec, geometry)
    clean = session.render_clean()
    hazy = session.level_renderer(clean).render(channel_extinction(300.0), 0).radiance
    far = np.isinf(session.pixels.distance_m) | (session.pixels.distance_m > 2000)
    assert not np.array_equal(hazy, clean)
    assert session.loaded.box_half_width_m >= 3 * (spec.haze.top_m + 60.0)
    assert abs(hazy[far].mean() - clean[far].mean()) > 0
