"""`seahaze export` (issue 18): dehazing and detection layouts of a finished dataset, as links.

Each dehazing layout is read by a loader written here after the convention of the code that
reads it (read, not copied): a paired loader that derives GT/<scene>.png from
hazy/<scene>_<level>.png; DehazeFormer's PairLoader (GT/<name> beside hazy/<name>); FFA-Net's
RESIDE loader (clear/<hazy name up to the first '_'>.png). Every pair must be the same scene and
camera at the same size, found through the files themselves (inodes, bytes), not the names.
"""

from __future__ import annotations

import csv
import errno
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from conftest import SPLIT_SCENES
from seahaze.cli import main
from seahaze.dataset.owned import RECORD_NAME
from seahaze.export import PAIR_COLUMNS, reside_ids

LEVELS = ("v0500", "v2000")


def _export(dataset: Path, out: Path, layout: str, *extra: str) -> int:
    return main(["export", str(dataset), "--layout", layout, "--out", str(out), *extra])


def _manifest(root: Path) -> dict:
    return json.loads((root / "dataset.json").read_text())


class DatasetFiles:
    """Which dataset image a file of an export is: by inode for links, else by content."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.by_inode: dict[tuple[int, int], tuple[str, str]] = {}
        self.by_bytes: dict[bytes, tuple[str, str]] = {}
        for path in (root / "images").glob("*/*.png"):
            key = (path.parent.name, path.stem)
            st = path.stat()
            self.by_inode[(st.st_dev, st.st_ino)] = key
            self.by_bytes[path.read_bytes()] = key

    def source(self, path: Path) -> tuple[str, str]:
        """(level, scene) of the dataset image ``path`` shows."""
        st = path.stat()  # follows a symbolic link
        return self.by_inode.get((st.st_dev, st.st_ino)) or self.by_bytes[path.read_bytes()]

    def camera(self, scene: str) -> dict:
        return json.loads((self.root / "meta" / f"{scene}.json").read_text())["camera"]


def _check_pair(files: DatasetFiles, hazy: Path, gt: Path, level: str, scene: str) -> None:
    """The pair is that scene's image at that level and its clean image, same size and camera."""
    hazy_level, hazy_scene = files.source(hazy)
    gt_level, gt_scene = files.source(gt)
    assert (hazy_level, gt_level) == (level, "clean")
    assert hazy_scene == gt_scene == scene
    assert files.camera(hazy_scene) == files.camera(gt_scene)
    with Image.open(hazy) as a, Image.open(gt) as b:
        assert a.size == b.size == tuple(files.camera(scene)["resolution"])
        pixels_a, pixels_b = np.asarray(a), np.asarray(b)
    assert pixels_a.shape == pixels_b.shape == (a.size[1], a.size[0], 3)


# --------------------------------------------------------------------------------------------
# Loaders after each convention


def paired_loader(split_dir: Path) -> list[tuple[Path, Path, str, str]]:
    """hazy/<scene>_<level>.png ↔ GT/<scene>.png: GT name = hazy name without its last '_…'."""
    pairs = []
    for hazy in sorted((split_dir / "hazy").iterdir()):
        scene, level = hazy.stem.rsplit("_", 1)
        pairs.append((hazy, split_dir / "GT" / f"{scene}.png", scene, level))
    return pairs


def dehazeformer_loader(split_dir: Path) -> list[tuple[Path, Path, str, str]]:
    """DehazeFormer's PairLoader: the GT folder's sorted names, each read in hazy/ and GT/."""
    names = sorted(os.listdir(split_dir / "GT"))
    out = []
    for name in names:
        scene, level = Path(name).stem.rsplit("_", 1)
        out.append((split_dir / "hazy" / name, split_dir / "GT" / name, scene, level))
    return out


def ffa_loader(split_dir: Path, ids: dict[str, str]) -> list[tuple[Path, Path, str, str]]:
    """FFA-Net's RESIDE_Dataset: listdir(hazy); id = name up to the first '_';
    clear/<id>.png."""
    scene_of = {ident: scene for scene, ident in ids.items()}
    out = []
    for name in os.listdir(split_dir / "hazy"):
        ident = name.split("_")[0]
        level = Path(name).stem.split("_", 1)[1]
        out.append(
            (
                split_dir / "hazy" / name,
                split_dir / "clear" / f"{ident}.png",
                scene_of[ident],
                level,
            )
        )
    return out


@pytest.fixture(scope="module")
def files(split_dataset) -> DatasetFiles:
    return DatasetFiles(split_dataset)


@pytest.fixture(scope="module")
def splits(split_dataset) -> dict[str, list[str]]:
    scenes = _manifest(split_dataset)["scenes"]
    out: dict[str, list[str]] = {}
    for name, entry in scenes.items():
        out.setdefault(entry["split"], []).append(name)
    assert sorted(out) == ["test", "train", "val"]
    return out


@pytest.mark.parametrize("layout", ["paired", "same-name", "reside"])
def test_dehazing_layouts_load_every_pair_of_every_split(
    layout, split_dataset, files, splits, tmp_path, capsys
):
    out = tmp_path / layout
    assert _export(split_dataset, out, layout) == 0
    said = capsys.readouterr().out
    assert f"{len(LEVELS) * SPLIT_SCENES} hazy/clean pairs" in said and "hard links" in said
    ids = reside_ids(list(_manifest(split_dataset)["scenes"]))
    loaders = {
        "paired": paired_loader,
        "same-name": dehazeformer_loader,
        "reside": lambda d: ffa_loader(d, ids),
    }
    seen: dict[str, set[str]] = {}
    for split, scenes in splits.items():
        pairs = loaders[layout](out / split)
        assert len(pairs) == len(scenes) * len(LEVELS)
        assert {(scene, level) for *_, scene, level in pairs} == {
            (s, lv) for s in scenes for lv in LEVELS
        }
        for hazy, gt, scene, level in pairs:
            _check_pair(files, hazy, gt, level, scene)
        seen[split] = {scene for *_, scene, _ in pairs}
    # Scene-disjoint: no scene in two split folders, every scene in one.
    all_scenes = [s for scenes in seen.values() for s in scenes]
    assert len(all_scenes) == len(set(all_scenes)) == SPLIT_SCENES


def test_pairs_csv_gives_visibility_and_sigma_of_every_hazy_image(split_dataset, splits, tmp_path):
    out = tmp_path / "paired"
    assert _export(split_dataset, out, "paired") == 0
    levels = {lv["name"]: lv for lv in _manifest(split_dataset)["levels"]}
    for split, scenes in splits.items():
        with (out / split / "pairs.csv").open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert tuple(rows[0]) == PAIR_COLUMNS
        assert len(rows) == len(scenes) * len(LEVELS)
        for row in rows:
            level = levels[row["level"]]
            assert float(row["visibility_m"]) == level["visibility_m"]
            assert float(row["sigma_per_m"]) == pytest.approx(3.912 / level["visibility_m"], 1e-3)
            assert float(row["sigma_per_m"]) == level["sigma_per_m"]
            assert row["split"] == split and row["scene"] in scenes
            assert (out / split / row["hazy"]).is_file() and (out / split / row["gt"]).is_file()
            assert Path(row["hazy"]).stem == f"{row['scene']}_{row['level']}"


def test_pairs_loaded_through_a_torch_dataloader(split_dataset, files, tmp_path):
    torch = pytest.importorskip("torch")
    out = tmp_path / "paired"
    assert _export(split_dataset, out, "paired") == 0

    class Paired(torch.utils.data.Dataset):
        def __init__(self, split_dir: Path) -> None:
            self.pairs = paired_loader(split_dir)

        def __len__(self) -> int:
            return len(self.pairs)

        def __getitem__(self, i: int):
            hazy, gt, scene, level = self.pairs[i]
            to_tensor = lambda p: torch.from_numpy(np.asarray(Image.open(p))).permute(2, 0, 1)  # noqa: E731
            return to_tensor(hazy), to_tensor(gt), scene, level

    loader = torch.utils.data.DataLoader(Paired(out / "train"), batch_size=2)
    batches = list(loader)
    assert sum(len(b[2]) for b in batches) == len(paired_loader(out / "train"))
    for hazy, gt, _scenes, _levels in batches:
        assert hazy.shape == gt.shape and hazy.shape[1:] == (3, 36, 64)
        assert not torch.equal(hazy, gt)  # haze changes the pixels


def test_yolo_layout_is_one_standard_dataset_per_level(split_dataset, splits, tmp_path):
    out = tmp_path / "yolo"
    assert _export(split_dataset, out, "yolo") == 0
    for level in ("clean", *LEVELS):
        data = yaml.safe_load((out / level / "data.yaml").read_text())
        assert "path" not in data  # resolved against the YAML's own folder
        assert {k: data[k] for k in ("train", "val", "test")} == {
            s: f"images/{s}" for s in ("train", "val", "test")
        }
        assert data["names"][0] == "container_ship"
        for split, scenes in splits.items():
            images = sorted(p.stem for p in (out / level / "images" / split).iterdir())
            assert images == sorted(scenes)
            for scene in scenes:
                label = out / level / "labels" / split / f"{scene}.txt"
                assert (
                    label.read_bytes()
                    == (split_dataset / "labels" / level / f"{scene}.txt").read_bytes()
                )
                assert os.path.samefile(
                    out / level / "images" / split / f"{scene}.png",
                    split_dataset / "images" / level / f"{scene}.png",
                )


def test_yolo_hazy_layout_trains_on_every_level_scene_disjoint(split_dataset, splits, tmp_path):
    """One Ultralytics dataset over the clean image and the levels: each scene's images, all
    levels, in its own split (train and val share no scene), each with its level's labels."""
    out = tmp_path / "hazy"
    assert _export(split_dataset, out, "yolo-hazy", "--levels", LEVELS[0]) == 0
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert "path" not in data and data["names"][0] == "container_ship"
    assert {k: data[k] for k in ("train", "val", "test")} == {
        s: f"images/{s}" for s in ("train", "val", "test")
    }
    scenes_in = {}
    for split, scenes in splits.items():
        names = sorted(p.stem for p in (out / "images" / split).iterdir())
        assert names == sorted(f"{s}_{lv}" for s in scenes for lv in ("clean", LEVELS[0]))
        scenes_in[split] = {name.rsplit("_", 1)[0] for name in names}
        for scene in scenes:
            for level in ("clean", LEVELS[0]):
                label = out / "labels" / split / f"{scene}_{level}.txt"
                assert (
                    label.read_bytes()
                    == (split_dataset / "labels" / level / f"{scene}.txt").read_bytes()
                )
                assert os.path.samefile(
                    out / "images" / split / f"{scene}_{level}.png",
                    split_dataset / "images" / level / f"{scene}.png",
                )
    assert not scenes_in["train"] & scenes_in["val"] and not scenes_in["train"] & scenes_in["test"]


# --------------------------------------------------------------------------------------------
# Links, refusals and ownership


@pytest.mark.parametrize(
    ("mode", "words"),
    [("hard", "hard links"), ("symlink", "symbolic links"), ("copy", "copies")],
)
def test_link_modes_place_the_same_bytes(split_dataset, tmp_path, capsys, mode, words):
    out = tmp_path / mode
    assert _export(split_dataset, out, "paired", "--link", mode) == 0
    assert f"({words}: {len(LEVELS) * SPLIT_SCENES + SPLIT_SCENES})" in capsys.readouterr().out
    for gt in out.glob("*/GT/*.png"):
        source = split_dataset / "images" / "clean" / gt.name
        assert gt.read_bytes() == source.read_bytes()
        assert gt.is_symlink() == (mode == "symlink")
        assert os.path.samefile(gt, source) == (mode != "copy")


def test_auto_falls_back_to_symlinks_then_copies(split_dataset, tmp_path, capsys, monkeypatch):
    def no_link(*_args, **_kwargs):
        raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))

    placed = len(LEVELS) * SPLIT_SCENES + SPLIT_SCENES  # hazy images, then one GT per scene
    monkeypatch.setattr(os, "link", no_link)
    assert _export(split_dataset, tmp_path / "a", "paired") == 0
    assert f"(symbolic links: {placed})" in capsys.readouterr().out
    assert all(p.is_symlink() for p in (tmp_path / "a").rglob("*.png"))
    monkeypatch.setattr(os, "symlink", no_link)
    assert _export(split_dataset, tmp_path / "b", "paired") == 0
    assert f"(copies: {placed})" in capsys.readouterr().out
    assert _export(split_dataset, tmp_path / "c", "paired", "--link", "hard") == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Invalid cross-device link" in err and "--link auto" in err


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("seahaze: error: ") and err.count("\n") == 1, err
    return err


def test_not_a_finished_dataset_is_refused(split_dataset, tmp_path, capsys):
    assert _export(tmp_path / "missing", tmp_path / "o1", "paired") == 2
    assert "not a folder" in _one_line_error(capsys)
    (tmp_path / "empty").mkdir()
    assert _export(tmp_path / "empty", tmp_path / "o2", "paired") == 2
    assert "dataset.json: missing; not a seahaze dataset" in _one_line_error(capsys)
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "dataset.json").write_text('{"format": "coco"}')
    assert _export(tmp_path / "other", tmp_path / "o3", "paired") == 2
    assert "not a seahaze dataset manifest" in _one_line_error(capsys)

    pending = tmp_path / "pending"
    shutil.copytree(split_dataset, pending)
    manifest = _manifest(pending)
    first = next(iter(manifest["scenes"]))
    manifest["scenes"][first]["status"] = "pending"
    (pending / "dataset.json").write_text(json.dumps(manifest))
    assert _export(pending, tmp_path / "o4", "paired") == 2
    assert f"1 of {SPLIT_SCENES} scenes are not done (e.g. {first}: pending)" in _one_line_error(
        capsys
    )
    manifest["scenes"][first]["status"] = "done"
    (pending / "dataset.json").write_text(json.dumps(manifest))
    (pending / "images" / "v2000" / f"{first}.png").unlink()
    assert _export(pending, tmp_path / "o5", "paired") == 2
    assert f"v2000/{first}.png: missing" in _one_line_error(capsys)
    assert not any((tmp_path / f"o{i}").exists() for i in range(1, 6))


def test_bad_level_and_output_inside_the_dataset_are_refused(split_dataset, tmp_path, capsys):
    assert _export(split_dataset, tmp_path / "o", "paired", "--levels", "v0900") == 2
    assert "--levels v0900: not a hazy level" in _one_line_error(capsys)
    assert _export(split_dataset, split_dataset / "export", "paired") == 2
    assert "inside the dataset" in _one_line_error(capsys)
    assert not (split_dataset / "export").exists()
    for empty in ("", ",,,"):  # once exported nothing, exit 0
        assert _export(split_dataset, tmp_path / "o", "paired", "--levels", empty) == 2
        assert "no level named" in _one_line_error(capsys)
    assert not (tmp_path / "o").exists()


def test_files_it_did_not_write_are_never_overwritten(split_dataset, splits, tmp_path, capsys):
    out = tmp_path / "mine"
    scene = splits["train"][0]
    mine = out / "train" / "GT" / f"{scene}.png"
    mine.parent.mkdir(parents=True)
    mine.write_bytes(b"my own file")
    notes = out / "notes.txt"
    notes.write_text("kept")
    assert _export(split_dataset, out, "paired") == 2
    err = _one_line_error(capsys)
    assert str(mine) in err and "never overwritten" in err
    assert mine.read_bytes() == b"my own file" and notes.read_text() == "kept"
    names = sorted(p.name for p in out.rglob("*"))
    assert names == sorted(["train", "GT", f"{scene}.png", "notes.txt"])  # nothing added


def test_a_new_export_replaces_its_own_files_and_removes_stale_ones(
    split_dataset, tmp_path, capsys
):
    out = tmp_path / "again"
    (out / "train").mkdir(parents=True)
    (out / "train" / "readme.txt").write_text("the user's")
    assert _export(split_dataset, out, "paired") == 0
    first = sorted(p.relative_to(out).as_posix() for p in out.rglob("*.png"))
    assert _export(split_dataset, out, "paired") == 0  # its own files: replaced
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*.png")) == first
    capsys.readouterr()
    assert _export(split_dataset, out, "paired", "--levels", "2000") == 0
    assert f"removed {SPLIT_SCENES} file(s) of an earlier export" in capsys.readouterr().out
    assert not list(out.rglob("*_v0500.png")) and len(list(out.rglob("*_v2000.png"))) == 6
    assert (out / "train" / "readme.txt").read_text() == "the user's"
    record = json.loads((out / RECORD_NAME).read_text())
    assert record["layout"] == "paired" and "train/readme.txt" not in record["files"]


def test_a_scene_of_an_unknown_split_is_refused_not_left_out(split_dataset, tmp_path, capsys):
    data = tmp_path / "edited"
    shutil.copytree(split_dataset, data)
    manifest = _manifest(data)
    scene = sorted(manifest["scenes"])[0]
    manifest["scenes"][scene]["split"] = "holdout"
    (data / "dataset.json").write_text(json.dumps(manifest))
    assert _export(data, tmp_path / "view", "paired") == 2
    err = _one_line_error(capsys)
    assert f"scene {scene!r} has split 'holdout'; allowed: train, val, test" in err
    assert not (tmp_path / "view").exists()
