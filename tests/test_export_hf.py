"""`seahaze export --layout hf`: a Hugging Face `datasets` folder of Parquet shards.

The export of rendered datasets is loaded with the real `datasets` library (offline, its cache
in a temporary folder) — every configuration and split, and streamed — and every field of every
row is checked against the dataset's own files: counts per split and level, the hazy and clean
pixels against the PNGs, the depth against the EXR, the boxes against the YOLO labels and the
COCO files, distance, contrast and the visible flag against the meta files and
`labels_visible/`, visibility, σ and regulation against `dataset.json`. Those tests are skipped
without `datasets` (`pip install 'seahaze[hf]'`). The plan (file names) and the card's
front-matter are checked without it, and so are the refusals.
"""

from __future__ import annotations

import importlib.util
import json
import struct
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from PIL import Image

from conftest import PAIR_SCENE, SPLIT_SCENES, TINY_SEQUENCE, cli_run
from seahaze.dataset.card import MSVD_CITATION
from seahaze.dataset.owned import RECORD_NAME
from seahaze.export.hf import plan_hf
from seahaze.export.source import open_finished
from seahaze.fileio import read_exr

LEVELS = ("v0500", "v2000")
SPLITS = ("train", "val", "test")
HAS_PYARROW = importlib.util.find_spec("pyarrow") is not None
NEEDS_PYARROW = pytest.mark.skipif(
    not HAS_PYARROW, reason="pyarrow is not installed: pip install 'seahaze[hf]'"
)


def export(dataset: Path, out: Path, *flags: str) -> tuple[int, str, str]:
    return cli_run(["export", str(dataset), "--layout", "hf", "--out", str(out), *flags], 120)


def manifest(root: Path) -> dict[str, Any]:
    return json.loads((root / "dataset.json").read_text())


def front_matter(card: str) -> dict[str, Any]:
    """The YAML between the card's first two ``---`` lines."""
    assert card.startswith("---\n")
    return yaml.safe_load(card.split("---\n", 2)[1])


# --------------------------------------------------------------------------------------------
# The plan and the card, without datasets or pyarrow


def test_the_plan_names_a_shard_per_level_and_split_and_a_card(split_dataset):
    plan = plan_hf(open_finished(split_dataset))
    splits = Counter(e["split"] for e in manifest(split_dataset)["scenes"].values())
    assert sorted(plan.built) == sorted(
        f"data/{level}/{split}-00000-of-00001.parquet" for level in LEVELS for split in SPLITS
    )
    assert list(plan.texts) == ["README.md"] and not plan.placed
    assert plan.pairs == SPLIT_SCENES * len(LEVELS) == sum(splits.values()) * len(LEVELS)


def test_the_card_front_matter_has_licence_tasks_and_a_config_per_level(split_dataset):
    card = plan_hf(open_finished(split_dataset)).texts["README.md"]
    front = front_matter(card)
    assert front["license"] == "other"
    assert front["task_categories"] == ["image-to-image", "object-detection", "depth-estimation"]
    assert front["size_categories"] == ["n<1K"]
    assert "dehazing" in front["tags"]
    configs = {c["config_name"]: c for c in front["configs"]}
    assert list(configs) == ["all", *LEVELS]
    assert configs["all"]["default"] is True
    assert not any(c.get("default") for name, c in configs.items() if name != "all")
    content = configs["all"]["description"].rsplit(" ", 1)[1]
    assert len(content) == 16 and int(content, 16) >= 0
    for name, config in configs.items():
        pattern = "*" if name == "all" else name
        what = "every level" if name == "all" else f"level {name}"
        assert config["description"] == f"{what}; seahaze export {content}"
        assert config["data_files"] == [
            {"split": split, "path": f"data/{pattern}/{split}-*.parquet"} for split in SPLITS
        ]
    # The body: the dataset card's description, what a row holds, the citation.
    assert "## Counts per split and class" in card and "## Levels" in card
    assert "`depth` | Image (float32 TIFF, mode `F`)" in card
    assert MSVD_CITATION in card
    assert "No licence was chosen" in card


def test_a_dataset_without_split_is_one_train_split(dataset):
    front = front_matter(plan_hf(open_finished(dataset)).texts["README.md"])
    assert [c["data_files"] for c in front["configs"]] == [
        [{"split": "train", "path": f"data/{pattern}/train-*.parquet"}]
        for pattern in ("*", "v0300", "v4000")
    ]


# --------------------------------------------------------------------------------------------
# Exports read with the real datasets library


@pytest.fixture(scope="module")
def hf(tmp_path_factory):
    """The real ``datasets``, its home (and so its default cache) in a temporary folder and
    offline: the environment says so before it is first imported (seahaze never imports it),
    and loading a local folder needs no network anyway. Skipped without it."""
    with pytest.MonkeyPatch.context() as patch:
        home = tmp_path_factory.mktemp("hf_home")
        for name, value in (
            ("HF_HOME", str(home)),
            ("HF_HUB_OFFLINE", "1"),
            ("HF_DATASETS_OFFLINE", "1"),
            ("HF_HUB_DISABLE_TELEMETRY", "1"),
        ):
            patch.setenv(name, value)
        datasets = pytest.importorskip(
            "datasets",
            reason="Hugging Face datasets is not installed: pip install 'seahaze[hf]'",
        )
        datasets.disable_progress_bars()
        yield datasets


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("hf_cache"))


@pytest.fixture(scope="module")
def split_view(split_dataset, tmp_path_factory) -> Path:
    if not HAS_PYARROW:
        pytest.skip("pyarrow is not installed: pip install 'seahaze[hf]'")
    out = tmp_path_factory.mktemp("hf") / "view"
    code, said, err = export(split_dataset, out)
    assert code == 0, err
    assert f"{SPLIT_SCENES * len(LEVELS)} hazy/clean pairs" in said and "6 Parquet file(s)" in said
    return out


class Source:
    """The dataset's own files, as the rows must show them."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.data = manifest(root)
        self.levels = {level["name"]: level for level in self.data["levels"]}
        self.coco: dict[str, dict[str, Any]] = {}

    def split(self, scene: str) -> str:
        return self.data["scenes"][scene].get("split", "train")

    def meta(self, scene: str) -> dict[str, Any]:
        return json.loads((self.root / "meta" / f"{scene}.json").read_text())

    def pixels(self, level: str, scene: str) -> np.ndarray:
        with Image.open(self.root / "images" / level / f"{scene}.png") as image:
            return np.asarray(image)

    def yolo(self, level: str, scene: str, folder: str = "labels") -> list[tuple[int, list]]:
        """(class, [x, y, w, h] px) of each line of a YOLO label file."""
        width, height = self.meta(scene)["camera"]["resolution"]
        text = (self.root / folder / level / f"{scene}.txt").read_text()
        boxes = []
        for line in text.splitlines():
            c, cx, cy, w, h = line.split()
            w_px, h_px = float(w) * width, float(h) * height
            x, y = float(cx) * width - w_px / 2, float(cy) * height - h_px / 2
            boxes.append((int(c), [x, y, w_px, h_px]))
        return boxes

    def coco_boxes(self, level: str, scene: str) -> list[tuple[int, list]]:
        """(class, bbox) of the scene's annotations in ``coco/<level>.json``, in order."""
        if level not in self.coco:
            self.coco[level] = json.loads((self.root / "coco" / f"{level}.json").read_text())
        coco = self.coco[level]
        image = next(
            i["id"] for i in coco["images"] if i["file_name"] == f"images/{level}/{scene}.png"
        )
        return [
            (a["category_id"] - 1, a["bbox"]) for a in coco["annotations"] if a["image_id"] == image
        ]


def check_row(source: Source, row: dict[str, Any], classes: list[str]) -> None:
    """Every field of ``row`` against the dataset's files."""
    scene, level = row["scene"], row["level"]
    entry = source.levels[level]
    meta = source.meta(scene)
    assert row["split"] == source.split(scene)
    assert row["sequence"] == source.data["scenes"][scene].get("sequence")
    assert row["frame"] == source.data["scenes"][scene].get("frame")
    assert row["visibility_m"] == entry["visibility_m"]
    assert row["sigma_per_m"] == entry["sigma_per_m"]
    assert row["regulation"] == entry["regulation"]
    level_meta = next(m for m in meta["levels"] if m["name"] == level)
    assert row["sigma_rgb_per_m"] == level_meta["sigma_rgb_per_m"]
    # Images: the PNGs' pixels; depth: the EXR's float32 values, inf for sky included.
    assert row["hazy"].mode == row["clean"].mode == "RGB"
    assert np.array_equal(np.asarray(row["hazy"]), source.pixels(level, scene))
    assert np.array_equal(np.asarray(row["clean"]), source.pixels("clean", scene))
    depth = np.asarray(row["depth"])
    expected = read_exr(source.root / "depth" / f"{scene}.exr")["Z"]
    assert row["depth"].mode == "F" and depth.dtype == np.float32
    assert np.array_equal(depth, expected) and np.isinf(depth).any()
    # Objects: the labelled vessels, boxes as the YOLO and COCO files give them.
    objects = row["objects"]
    labelled = [v for v in meta["vessels"] if v["box_px"] is not None]
    assert objects["vessel"] == [v["index"] for v in labelled]
    assert objects["track_id"] == [v.get("track_id") for v in labelled]
    assert objects["category"] == [v["class_id"] for v in labelled]
    assert [classes[c] for c in objects["category"]] == [v["class"] for v in labelled]
    yolo = source.yolo(level, scene)
    assert [c for c, _ in yolo] == objects["category"]
    for (_, box), bbox in zip(yolo, objects["bbox"], strict=True):
        assert np.allclose(box, bbox, atol=1e-3)  # 6 decimals of a 64 px width
    coco = source.coco_boxes(level, scene)  # converted from the YOLO files' 6 decimals
    assert [c for c, _ in coco] == objects["category"]
    for (_, box), bbox in zip(coco, objects["bbox"], strict=True):
        assert np.allclose(box, bbox, atol=1e-3)
    assert objects["distance_m"] == [v["distance_m"] for v in labelled]
    assert objects["visible_fraction"] == [v["visible_fraction"] for v in labelled]
    looks = [v["levels"][level] for v in labelled]
    assert objects["apparent_contrast"] == [look["apparent_contrast"] for look in looks]
    assert objects["local_contrast"] == [look["local_contrast"] for look in looks]
    assert objects["visible"] == [look["discernible"] for look in looks]
    assert objects["beyond_visibility"] == [look["beyond_visibility"] for look in looks]
    visible_labels = source.root / "labels_visible" / level / f"{scene}.txt"
    if visible_labels.is_file():  # labels.write_visible: its lines are the visible vessels'
        seen = [box for box, flag in zip(yolo, objects["visible"], strict=True) if flag]
        assert source.yolo(level, scene, "labels_visible") == seen


def test_load_dataset_gives_every_row_with_every_field_of_the_source(
    hf, cache, split_dataset, split_view
):
    source = Source(split_dataset)
    loaded = hf.load_dataset(str(split_view), cache_dir=cache)
    assert sorted(loaded) == sorted(SPLITS)
    classes = manifest(split_dataset)["classes"]
    features = loaded["train"].features
    assert features["hazy"] == features["clean"] == features["depth"] == hf.Image()
    assert features["visibility_m"] == hf.Value("float64")
    assert features["objects"]["category"].feature.names == classes
    scenes = {
        split: [s for s in source.data["scenes"] if source.split(s) == split] for split in SPLITS
    }
    for split in SPLITS:
        rows = list(loaded[split])
        # Every (scene, level) of the split once: the default configuration holds every level.
        assert Counter((r["scene"], r["level"]) for r in rows) == Counter(
            (scene, level) for scene in scenes[split] for level in LEVELS
        )
        for row in rows:
            check_row(source, row, classes)


def test_each_level_is_a_configuration_and_streams_the_same_rows(
    hf, cache, split_dataset, split_view
):
    source = Source(split_dataset)
    for level in LEVELS:
        for split in SPLITS:
            part = hf.load_dataset(str(split_view), level, split=split, cache_dir=cache)
            scenes = [s for s in source.data["scenes"] if source.split(s) == split]
            assert part["scene"] == scenes and set(part["level"]) == {level}
            streamed = list(hf.load_dataset(str(split_view), level, split=split, streaming=True))
            assert [r["scene"] for r in streamed] == scenes
            for row, again in zip(part, streamed, strict=True):
                assert np.array_equal(np.asarray(row["hazy"]), np.asarray(again["hazy"]))
                assert np.array_equal(np.asarray(row["depth"]), np.asarray(again["depth"]))
                assert row["objects"] == again["objects"]


def test_the_card_is_the_hub_card_and_its_patterns_find_every_shard(split_view):
    card = (split_view / "README.md").read_text()
    front = front_matter(card)
    shards = {p.relative_to(split_view).as_posix() for p in split_view.glob("data/*/*.parquet")}
    found = set()
    for config in front["configs"]:
        for files in config["data_files"]:
            matched = {p.relative_to(split_view).as_posix() for p in split_view.glob(files["path"])}
            assert matched and all(f"/{files['split']}-" in m for m in matched)
            found |= matched
    assert found == shards and len(shards) == len(LEVELS) * len(SPLITS)
    record = json.loads((split_view / RECORD_NAME).read_text())
    assert set(record["files"]) == {*shards, "README.md"}


@pytest.fixture(scope="module")
def pair_dataset(tmp_path_factory) -> Path:
    """One scene with ``labels.write_visible``: a boat seen at 300 m and a ship that is not."""
    root = tmp_path_factory.mktemp("hf_pair")
    (root / "pair.yaml").write_text(PAIR_SCENE.replace("WRITE", "true"))
    code, _, err = cli_run(["render", str(root / "pair.yaml"), "--out", str(root / "ds")], 300)
    assert code == 0, err
    return root / "ds"


def test_the_visible_flags_are_the_visible_labels(hf, cache, pair_dataset, tmp_path):
    if not HAS_PYARROW:
        pytest.skip("pyarrow is not installed: pip install 'seahaze[hf]'")
    assert export(pair_dataset, tmp_path / "view")[0] == 0
    rows = list(hf.load_dataset(str(tmp_path / "view"), split="train", cache_dir=cache))
    source = Source(pair_dataset)
    classes = source.data["classes"]
    flags = {row["level"]: row["objects"]["visible"] for row in rows}
    assert flags == {"v0300": [True, False], "v4000": [True, True]}  # boat, ship
    for row in rows:
        check_row(source, row, classes)


def test_a_sequence_has_its_name_frames_and_track_ids(hf, cache, tmp_path):
    if not HAS_PYARROW:
        pytest.skip("pyarrow is not installed: pip install 'seahaze[hf]'")
    (tmp_path / "seq.yaml").write_text(TINY_SEQUENCE)
    code, _, err = cli_run(
        ["render", str(tmp_path / "seq.yaml"), "--out", str(tmp_path / "ds")], 300
    )
    assert code == 0, err
    assert export(tmp_path / "ds", tmp_path / "view")[0] == 0
    rows = list(hf.load_dataset(str(tmp_path / "view"), split="train", cache_dir=cache))
    assert [(r["sequence"], r["frame"]) for r in rows] == [("tinyseq", i) for i in range(3)]
    # Track ids are the vessel index + 1 in every frame (docs/dataset-format.md#sequences).
    assert all(r["objects"]["track_id"] == [v + 1 for v in r["objects"]["vessel"]] for r in rows)
    assert any(r["objects"]["vessel"] for r in rows)
    source = Source(tmp_path / "ds")
    for row in rows:
        check_row(source, row, source.data["classes"])


def test_a_dataset_without_split_loads_as_train(hf, cache, dataset, tmp_path):
    if not HAS_PYARROW:
        pytest.skip("pyarrow is not installed: pip install 'seahaze[hf]'")
    code, _, err = export(dataset, tmp_path / "view", "--license", "cc-by-4.0")
    assert code == 0, err
    loaded = hf.load_dataset(str(tmp_path / "view"), cache_dir=cache)
    assert list(loaded) == ["train"]
    assert sorted(loaded["train"]["level"]) == ["v0300", "v4000"]
    assert set(loaded["train"]["split"]) == {"train"}
    source = Source(dataset)
    for row in loaded["train"]:
        check_row(source, row, source.data["classes"])
    card = (tmp_path / "view" / "README.md").read_text()
    assert front_matter(card)["license"] == "cc-by-4.0" and "`cc-by-4.0`, as chosen" in card


# --------------------------------------------------------------------------------------------
# Exporting again, and refusals


@NEEDS_PYARROW
def test_exporting_fewer_levels_again_removes_the_other_levels_shards(split_dataset, tmp_path):
    out = tmp_path / "view"
    assert export(split_dataset, out)[0] == 0
    code, said, err = export(split_dataset, out, "--levels", "v2000")
    assert code == 0, err
    assert "removed 3 file(s) of an earlier export" in said
    assert sorted(p.parent.name for p in out.glob("data/*/*.parquet")) == ["v2000"] * 3
    assert [c["config_name"] for c in front_matter((out / "README.md").read_text())["configs"]] == [
        "all",
        "v2000",
    ]


def test_a_new_export_into_the_same_folder_is_not_loaded_from_the_old_cache(
    hf, split_dataset, tmp_path
):
    """``datasets`` caches a local folder by its name and its card's configurations, not by
    its files: the content id in each configuration's description tells two exports apart."""
    import shutil

    if not HAS_PYARROW:
        pytest.skip("pyarrow is not installed: pip install 'seahaze[hf]'")
    ds = tmp_path / "ds"
    shutil.copytree(split_dataset, ds)
    out, cache = tmp_path / "view", str(tmp_path / "cache")
    assert export(ds, out)[0] == 0
    first = hf.load_dataset(str(out), "v0500", split="train", cache_dir=cache)["scene"]
    data = manifest(ds)
    names = list(data["scenes"])
    for name in names:  # another split of the same scenes: every file as it was
        data["scenes"][name]["split"] = "train" if name in names[:4] else "val"
    (ds / "dataset.json").write_text(json.dumps(data))
    assert export(ds, out)[0] == 0
    second = hf.load_dataset(str(out), "v0500", split="train", cache_dir=cache)["scene"]
    assert list(second) == names[:4] and list(first) != names[:4]


def test_without_pyarrow_the_export_names_the_extra(split_dataset, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # what `import pyarrow` meets without it
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    code, _, err = export(split_dataset, tmp_path / "view")
    assert code == 2 and not (tmp_path / "view").exists()
    assert err.count("\n") == 1 and "pip install 'seahaze[hf]'" in err and "pyarrow" in err


def exr_chunk_data(data: bytes) -> tuple[int, int]:
    """(offset, length) of the compressed pixels of the first chunk of a scanline EXR."""
    pos = 8
    while data[pos] != 0:  # attributes: name\0 type\0 size data
        pos = data.index(b"\0", data.index(b"\0", pos) + 1) + 1
        (size,) = struct.unpack_from("<i", data, pos)
        pos += 4 + size
    first = struct.unpack_from("<Q", data, pos + 1)[0]
    _y, length = struct.unpack_from("<ii", data, first)
    return first + 8, length


@NEEDS_PYARROW
def test_a_depth_that_cannot_be_decoded_refuses_the_export_and_leaves_nothing(
    split_dataset, tmp_path
):
    """The EXR's structure is intact (so the plan's check passes) but a chunk's compressed
    pixels are garbage: the shards being built are removed and no folder is left."""
    import shutil

    ds = tmp_path / "ds"
    shutil.copytree(split_dataset, ds)
    scenes = list(manifest(ds)["scenes"])
    depth = ds / "depth" / f"{scenes[-1]}.exr"
    data = bytearray(depth.read_bytes())
    start, length = exr_chunk_data(bytes(data))
    data[start : start + length] = bytes([0x5A]) * length
    depth.write_bytes(bytes(data))
    out = tmp_path / "a" / "view"
    code, said, err = export(ds, out)
    assert code == 2, (said, err)
    lines = [line for line in err.splitlines() if line.startswith("seahaze:")]
    assert len(lines) == 1 and str(depth) in lines[0] and "cannot read the depth" in lines[0]
    assert not (tmp_path / "a").exists()


@NEEDS_PYARROW
@pytest.mark.parametrize(
    ("damage", "words"),
    [
        ("label_line", ("has 1 boxes where the scene's meta labels 2 vessels",)),
        ("label_box", ("line 1 is not the box of vessel",)),
        ("meta_box", ("box_px", "allowed: x1 > x0 and y1 > y0")),
        ("meta_level", ("levels.v2000", "allowed: a mapping")),
        ("meta_class", ("class_id", "allowed: an integer, 0 to 8")),
        ("meta_json", ("cannot read the scene's meta",)),
        ("png_size", ("is 32x18, not 64x36",)),
    ],
)
def test_damaged_scene_files_are_refused_in_one_line(damage, words, split_dataset, tmp_path):
    import shutil

    ds = tmp_path / "ds"
    shutil.copytree(split_dataset, ds)
    data = manifest(ds)
    scene = next(
        s
        for s in data["scenes"]
        if sum(
            v["box_px"] is not None
            for v in json.loads((ds / "meta" / f"{s}.json").read_text())["vessels"]
        )
        >= 2
    )
    meta_path = ds / "meta" / f"{scene}.json"
    meta = json.loads(meta_path.read_text())
    labelled = [v for v in meta["vessels"] if v["box_px"] is not None]
    label = ds / "labels" / "v2000" / f"{scene}.txt"
    damaged = meta_path
    if damage == "label_line":
        label.write_text(label.read_text().splitlines()[0] + "\n")
        damaged = label
    elif damage == "label_box":
        first, *rest = label.read_text().splitlines()
        c, cx, *tail = first.split()
        label.write_text("\n".join([" ".join([c, f"{float(cx) + 0.01:.6f}", *tail]), *rest]) + "\n")
        damaged = label
    elif damage == "meta_box":
        labelled[0]["box_px"] = [10, 10, 5, 20]
    elif damage == "meta_level":
        labelled[0]["levels"]["v2000"] = None
    elif damage == "meta_class":
        labelled[0]["class_id"] = 99
    elif damage == "png_size":
        damaged = ds / "images" / "v0500" / f"{scene}.png"
        Image.new("RGB", (32, 18)).save(damaged)
    if damage.startswith("meta"):
        meta_path.write_text("{" if damage == "meta_json" else json.dumps(meta))
    out = tmp_path / "view"
    code, said, err = export(ds, out)
    assert code == 2, (said, err)
    assert err.count("\n") == 1 and str(damaged) in err, err
    for word in words:
        assert word in err, (word, err)
    assert not out.exists()


@pytest.mark.parametrize(
    ("flags", "words"),
    [
        (["--license", "CC BY 4.0"], ("--license 'CC BY 4.0'", "cc-by-4.0")),
        (["--license", "x" * 65], ("--license", "at most 64")),
    ],
)
def test_a_bad_licence_is_refused(flags, words, split_dataset, tmp_path):
    code, _, err = export(split_dataset, tmp_path / "view", *flags)
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "view").exists()
    for word in words:
        assert word in err


def test_a_licence_for_another_layout_is_refused(split_dataset, tmp_path):
    args = ["export", str(split_dataset), "--layout", "paired", "--out", str(tmp_path / "v")]
    code, _, err = cli_run([*args, "--license", "mit"])
    assert code == 2 and "only --layout hf writes a licence" in err
    assert not (tmp_path / "v").exists()
