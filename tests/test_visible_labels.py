"""Per-level visible-object labels (``labels.write_visible``) and the local-background contrast
they are chosen by (:mod:`seahaze.visible`), beside the MSVD protocol's labels of every vessel.

The definition is checked on synthetic images against a plain per-pixel re-computation (rows of
one elevation each, so "the ring pixels at the nearest elevation" is "the ring pixels in its
row"); the labels on a rendered scene built so the answer is known: a fishing boat at 150 m and
a container ship at 2 km. At V = 300 m the boat's transmittance is exp(-3.912 · 0.5) = 0.14 and
it shows as a faint hull and cabin; the ship's is exp(-26) and the fog beside it is all there
is. At V = 4000 m the ship's transmittance is still 0.14 (|C| = 0.06: its containers and bridge
show faintly). A ship at 3 km there (transmittance 0.05) sits on the 2 % threshold (read -0.021
with this scene's seed), so it would not make a test of "kept".
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import PAIR_SCENE
from seahaze.cli import main
from seahaze.dataset.layout import Layout
from seahaze.labels import Box
from seahaze.visible import LocalContrast, local_contrasts, visible_boxes

pytestmark = pytest.mark.usefixtures("mitsuba_variant")

RING = 3
"""The ring width the definition uses (px); the re-computation below does not import it."""


# ------------------------------------------------------------------------------------------
# The definition, on synthetic images


def grid(rows: int, cols: int, horizon_row: int) -> tuple[np.ndarray, np.ndarray]:
    """Elevation (deg, 0.5 per row, one value per row) and distance (inf above the horizon
    row: the sky) of a level camera's frame."""
    elevation = np.repeat((horizon_row - np.arange(rows) - 0.5)[:, None] * 0.5, cols, axis=1)
    distance = np.where(np.arange(rows)[:, None] < horizon_row, np.inf, 500.0)
    return elevation.astype(np.float32), np.broadcast_to(distance, (rows, cols)).copy()


def grey(y: np.ndarray) -> np.ndarray:
    """An RGB image whose luminance is ``y`` whatever the weights (they sum to 1)."""
    return np.repeat(y[..., None], 3, axis=2)


def expected_contrast(
    y: np.ndarray, y_ref: np.ndarray, instance: np.ndarray, vessel: int
) -> tuple[float, str]:
    """The definition spelled out pixel by pixel for images whose rows each hold one elevation:
    a vessel pixel's background is the mean of the non-vessel pixels of its own row within RING
    of the box; pixels brighter than that in the reference form one part, the others another;
    the vessel's contrast is the part's (mean - mean background) / mean background with the
    larger magnitude, among parts of two pixels or more."""
    pixels = [(r, c) for r, c in zip(*np.nonzero(instance == vessel), strict=True)]
    c0, c1 = min(c for _, c in pixels), max(c for _, c in pixels)
    width = instance.shape[1]
    parts: dict[str, list[tuple[float, float]]] = {"brighter": [], "darker": []}
    for r, c in pixels:
        ring = [
            cc for cc in range(max(0, c0 - RING), min(width, c1 + RING + 1)) if instance[r, cc] < 0
        ]
        assert ring  # every row of these scenes has background beside the vessel
        background = sum(float(y[r, cc]) for cc in ring) / len(ring)
        reference = sum(float(y_ref[r, cc]) for cc in ring) / len(ring)
        name = "brighter" if y_ref[r, c] > reference else "darker"
        parts[name].append((float(y[r, c]), background))
    best: tuple[float, str] | None = None
    for name, values in parts.items():
        if len(values) < 2:
            continue
        vessel_mean = sum(v for v, _ in values) / len(values)
        background_mean = sum(b for _, b in values) / len(values)
        contrast = (vessel_mean - background_mean) / background_mean
        if best is None or abs(contrast) > abs(best[0]):
            best = (contrast, name)
    assert best is not None
    return best


def scene_with_two_vessels(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A 16×24 frame: sky brightening upwards, sea darkening downwards, Monte Carlo-like noise;
    vessel 0 across the horizon with a bright superstructure over a dark hull, vessel 1 right
    beside it (inside vessel 0's ring, so it must not count as background). Returns the level's
    and the clean luminance, the instance map and the elevation."""
    rng = np.random.default_rng(seed)
    rows, cols, horizon = 16, 24, 7
    elevation, _ = grid(rows, cols, horizon)
    row = np.arange(rows)[:, None]
    background = np.where(row < horizon, 1.0 + 0.05 * (horizon - row), 0.3 - 0.01 * (row - horizon))
    clean = np.broadcast_to(background, (rows, cols)) * rng.uniform(0.97, 1.03, (rows, cols))
    instance = np.full((rows, cols), -1, dtype=np.int32)
    instance[4:10, 6:12] = 0
    instance[5:9, 12:15] = 1
    clean = clean.copy()
    clean[4:7, 6:12] *= 1.6  # superstructure against the sky: brighter
    clean[7:10, 6:12] *= 0.5  # hull against the sea: darker
    clean[5:9, 12:15] = 5.0  # a bright neighbour
    # The level: haze scales the contrast down and adds a uniform airlight.
    level = 0.2 * clean + 0.8 * 0.9 + rng.normal(0.0, 0.002, (rows, cols))
    return level, clean, instance, elevation


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_local_contrast_matches_a_pixel_by_pixel_computation(seed):
    level, clean, instance, elevation = scene_with_two_vessels(seed)
    _, distance = grid(*instance.shape, 7)
    for image in (level, clean):
        measured = local_contrasts(grey(image), instance, distance, elevation, 2, grey(clean))
        for vessel in (0, 1):
            contrast, part = expected_contrast(image, clean, instance, vessel)
            assert measured[vessel].contrast == pytest.approx(contrast, rel=1e-9, abs=1e-12)
            assert measured[vessel].part == part


def test_sky_share_tells_what_the_deciding_part_is_seen_against():
    _, clean, instance, elevation = scene_with_two_vessels(0)
    _, distance = grid(*instance.shape, 7)
    (boat, _) = local_contrasts(grey(clean), instance, distance, elevation, 2, grey(clean))
    # The bright superstructure (rows 4-6, above the horizon row 7) decides: all sky behind.
    assert boat.part == "brighter" and boat.sky_share == pytest.approx(1.0)


def test_a_vessel_equal_to_what_is_behind_it_is_not_seen_though_its_ring_differs():
    # Against a steep vertical gradient (the fogged sea darkens fast below the horizon) a
    # vessel whose pixels equal their rows' background has no contrast; the mean of a ring
    # around its box (rows above and below included) differs from the vessel's by over 2 %.
    rows, cols = 20, 20
    elevation, distance = grid(rows, cols, 0)  # all sea
    y = np.broadcast_to(np.exp(-0.2 * np.arange(rows))[:, None], (rows, cols)).copy()
    instance = np.full((rows, cols), -1, dtype=np.int32)
    instance[6:9, 5:15] = 0
    (measured,) = local_contrasts(grey(y), instance, distance, elevation, 1)
    assert measured.contrast == pytest.approx(0.0, abs=1e-12)
    assert not measured.discernible("koschmieder")
    ring = (instance < 0) & (np.arange(rows)[:, None] >= 3) & (np.arange(rows)[:, None] <= 11)
    assert abs(y[instance == 0].mean() / y[ring].mean() - 1.0) > 0.02


def test_bright_and_dark_parts_that_cancel_in_the_mean_are_still_seen():
    # Half the vessel 10 % brighter, half 10 % darker than the uniform sea behind it: the mean
    # has no contrast, each half has 10 %.
    elevation, distance = grid(10, 10, 0)
    y = np.full((10, 10), 0.5)
    instance = np.full((10, 10), -1, dtype=np.int32)
    instance[4:6, 3:7] = 0
    y[4, 3:7], y[5, 3:7] = 0.55, 0.45
    (measured,) = local_contrasts(grey(y), instance, distance, elevation, 1)
    assert y[instance == 0].mean() == pytest.approx(0.5)
    assert abs(measured.contrast) == pytest.approx(0.1)
    assert measured.discernible("mor")


def test_a_lone_pixel_does_not_decide_while_a_larger_part_exists():
    elevation, distance = grid(10, 10, 0)
    y = np.full((10, 10), 0.5)
    instance = np.full((10, 10), -1, dtype=np.int32)
    instance[4:6, 3:7] = 0
    y[4:6, 3:7] = 0.49  # -2 %: under the threshold
    y[4, 3] = 2.0  # one bright pixel, 300 % (a firefly)
    (measured,) = local_contrasts(grey(y), instance, distance, elevation, 1)
    assert measured.part == "darker" and measured.contrast == pytest.approx(-0.02)
    assert not measured.discernible("koschmieder")


def test_the_threshold_is_the_datasets():
    assert LocalContrast(-0.03).discernible("koschmieder")
    assert not LocalContrast(-0.03).discernible("mor")
    assert LocalContrast(0.06).discernible("mor")
    assert not LocalContrast(0.02).discernible("koschmieder")  # "exceeds": strictly above
    assert not LocalContrast(None).discernible("koschmieder")


def test_a_vessel_without_pixels_has_no_contrast_and_keeps_no_box():
    elevation, distance = grid(8, 8, 2)
    instance = np.full((8, 8), -1, dtype=np.int32)
    instance[3:5, 3:5] = 1
    y = np.full((8, 8), 0.4)
    y[3:5, 3:5] = 0.1
    measured = local_contrasts(grey(y), instance, distance, elevation, 2)
    assert measured[0] == LocalContrast(None)
    boxes = [Box(0, 0, 0, 0, 1, 1, 1), Box(1, 4, 3, 3, 5, 5, 4)]
    assert [b.vessel for b in visible_boxes(boxes, measured, "koschmieder")] == [1]


def test_scene_files_list_the_visible_labels_only_with_the_option(tmp_path):
    layout = Layout(tmp_path)
    plain = layout.scene_files("s", ["v0300"], exr=False)
    assert not any("labels_visible" in p.parts for p in plain)
    with_visible = layout.scene_files("s", ["v0300"], exr=False, visible=True)
    assert [p for p in with_visible if p not in plain] == [
        layout.visible_label("clean", "s"),
        layout.visible_label("v0300", "s"),
    ]


# ------------------------------------------------------------------------------------------
# A rendered scene whose answer is known (conftest.PAIR_SCENE)

NEAR, FAR = 0, 1
LEVELS = ["clean", "v0300", "v4000"]


def render_pair(root: Path, write_visible: bool) -> Path:
    scene = root / "pair.yaml"
    scene.write_text(PAIR_SCENE.replace("WRITE", "true" if write_visible else "false"))
    out = root / "out"
    assert main(["render", str(scene), "--out", str(out), "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def pair(tmp_path_factory) -> Path:
    return render_pair(tmp_path_factory.mktemp("visible"), True)


def box_lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def test_every_level_keeps_every_vessel_in_labels(pair):
    # The MSVD protocol, unchanged: both vessels at every level.
    texts = {(pair / "labels" / level / "pair.txt").read_text() for level in LEVELS}
    assert len(texts) == 1 and len(texts.pop().splitlines()) == 2


def test_visible_labels_drop_the_ship_hidden_in_fog_and_keep_the_boat(pair):
    meta = json.loads((pair / "meta" / "pair.json").read_text())
    near, far = (meta["vessels"][i] for i in (NEAR, FAR))
    every = box_lines(pair / "labels" / "clean" / "pair.txt")
    # Lines follow the vessel index; the boat's class id is its own.
    near_line = next(line for line in every if int(line.split()[0]) == near["class_id"])
    far_line = next(line for line in every if int(line.split()[0]) == far["class_id"])
    visible = {level: box_lines(pair / "labels_visible" / level / "pair.txt") for level in LEVELS}
    assert visible["clean"] == every
    assert visible["v0300"] == [near_line]
    assert visible["v4000"] == every
    assert far_line not in visible["v0300"]
    # What the labels follow, with the margins this scene was built for.
    assert abs(near["levels"]["v0300"]["local_contrast"]) > 0.04
    assert abs(far["levels"]["v0300"]["local_contrast"]) < 0.01
    assert abs(far["levels"]["v4000"]["local_contrast"]) > 0.03
    for vessel in (near, far):
        for level in LEVELS:
            entry = vessel["levels"][level]
            kept = abs(entry["local_contrast"]) > 0.02
            assert entry["discernible"] == kept
            assert entry["local_part"] in ("brighter", "darker")
            assert 0.0 <= entry["local_sky_share"] <= 1.0


def test_visible_coco_holds_the_visible_boxes_of_the_same_images(pair):
    for level, count in (("clean", 2), ("v0300", 1), ("v4000", 2)):
        every = json.loads((pair / "coco" / f"{level}.json").read_text())
        seen = json.loads((pair / "coco_visible" / f"{level}.json").read_text())
        assert seen["images"] == every["images"]
        assert seen["categories"] == every["categories"]
        assert len(every["annotations"]) == 2 and len(seen["annotations"]) == count
        boxes = {tuple(a["bbox"]) for a in every["annotations"]}
        assert {tuple(a["bbox"]) for a in seen["annotations"]} <= boxes


def test_without_the_option_the_dataset_is_as_before(pair, tmp_path):
    plain = render_pair(tmp_path, False)
    assert not (plain / "labels_visible").exists() and not (plain / "coco_visible").exists()

    def digests(root: Path) -> dict[str, str]:
        kinds = ("images", "labels", "meta", "depth", "coco")
        return {
            p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for kind in kinds
            for p in sorted((root / kind).rglob("*"))
            if p.is_file()
        }

    assert digests(plain) == digests(pair)


def test_resume_checks_and_force_prunes_the_visible_labels(pair, tmp_path):
    """A finished scene's visible labels are part of its files: a damaged one is found by the
    content hash and rendered again; ``--force`` for fewer levels deletes those of the level
    dropped, and its visible COCO file."""
    import shutil

    out = tmp_path / "out"
    shutil.copytree(pair, out)
    scene = tmp_path / "pair.yaml"
    scene.write_text(PAIR_SCENE.replace("WRITE", "true"))
    damaged = out / "labels_visible" / "v0300" / "pair.txt"
    original = damaged.read_bytes()
    damaged.write_text("")  # a valid, empty label file: only the content hash tells
    code, stdout, err = run_cli(["render", str(scene), "--out", str(out)])
    assert code == 0 and "content hash differs" in err and "wrote 1 scene(s)" in stdout
    assert damaged.read_bytes() == original
    code, _, err = run_cli(["render", str(scene), "--out", str(out), "--vis", "4000", "--force"])
    assert code == 0, err
    assert not (out / "labels_visible" / "v0300").exists()
    assert not (out / "coco_visible" / "v0300.json").exists()
    assert (out / "labels_visible" / "v4000" / "pair.txt").read_bytes() == (
        pair / "labels_visible" / "v4000" / "pair.txt"
    ).read_bytes()


def run_cli(args: list[str]) -> tuple[int, str, str]:
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([*args, "--quiet"])
    return code, out.getvalue(), err.getvalue()


def test_the_hazy_training_export_takes_the_visible_labels(pair, tmp_path):
    """``export --layout yolo-hazy`` of a dataset with visible-object labels trains on what
    each level shows: the ship hidden at 300 m has no box in that image's label file."""
    out = tmp_path / "view"
    assert main(["export", str(pair), "--layout", "yolo-hazy", "--out", str(out)]) == 0
    (split,) = [p.name for p in (out / "labels").iterdir()]
    for level in LEVELS:
        exported = out / "labels" / split / f"pair_{level}.txt"
        assert exported.read_bytes() == (pair / "labels_visible" / level / "pair.txt").read_bytes()
    assert len(box_lines(out / "labels" / split / "pair_v0300.txt")) == 1
    assert "labels_visible/" in (out / "data.yaml").read_text()
