"""End to end: `seahaze render` writes the whole dataset layout, deterministically."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from seahaze.cli import main
from seahaze.fileio import read_exr

ROOT = Path(__file__).resolve().parents[1]
LEVELS = ["v0300", "v4000"]


def test_layout_is_complete(dataset):
    for level in ["clean", *LEVELS]:
        image = Image.open(dataset / "images" / level / "default.png")
        assert image.size == (64, 36) and image.mode == "RGB"
        assert (dataset / "labels" / level / "default.txt").exists()
        assert (dataset / "exr" / level / "default.exr").exists()
    assert (dataset / "depth" / "default.exr").exists()
    meta = json.loads((dataset / "meta" / "default.json").read_text())
    assert [lv["name"] for lv in meta["levels"]] == LEVELS
    # The fixture renders 2 spp: the vessel-light pass takes a fourteenth, rounded up, so 1.
    render = meta["render"]
    assert render["spp"] == 2 and render["sampler"] == "multijitter"
    assert render["vessel_light"] == {"spp": 1, "smoothing_radius_px": 6}


def test_labels_are_identical_at_every_level(dataset):
    texts = {
        (dataset / "labels" / level / "default.txt").read_text() for level in ["clean", *LEVELS]
    }
    assert len(texts) == 1


def test_data_yaml_has_names_and_one_split_per_level(dataset):
    data = yaml.safe_load((dataset / "data.yaml").read_text())
    assert Path(data["path"]).is_absolute() and data["train"] == "images/clean"
    for level in ["clean", *LEVELS]:
        # Absolute: Ultralytics resolves only train/val/test against 'path' (issue 18).
        assert data[level] == str(dataset.resolve() / "images" / level)
    assert data["names"][0] == "container_ship"


def test_manifest_lists_levels_with_sigma_and_class(dataset):
    manifest = json.loads((dataset / "dataset.json").read_text())
    level = manifest["levels"][0]
    assert level["name"] == "v0300" and level["sigma_per_m"] == pytest.approx(3.912 / 300, rel=1e-3)
    assert level["regulation"] == "strict"
    assert manifest["scenes"]["default"]["status"] == "done"


def test_depth_is_finite_for_sea_and_inf_for_sky(dataset):
    depth = read_exr(dataset / "depth" / "default.exr")["Z"]
    assert depth.shape == (36, 64)
    assert np.isinf(depth[0]).all()  # top row: sky
    assert np.isfinite(depth[-1]).all() and (depth[-1] > 0).all()  # bottom row: sea


def test_haze_hides_the_horizon(dataset):
    def load(level):
        return read_exr(dataset / "exr" / level / "default.exr")["RGB"].mean(axis=-1)

    clean, thin, thick = load("clean"), load("v4000"), load("v0300")
    depth = read_exr(dataset / "depth" / "default.exr")["Z"]
    # The horizon: the lowest three sky rows against the sea farther than 1.5 km. Their
    # contrast falls as the visibility falls. (At 300 m it does not vanish: the fog seen just
    # above the dark sea, which absorbs the downwelling light, is darker than the fog above.)
    sky_rows = np.flatnonzero(np.isinf(depth).all(axis=1))[-3:]
    far_sea = np.isfinite(depth) & (depth > 1500.0)
    assert len(sky_rows) == 3 and far_sea.sum() >= 20

    def contrast(img):
        sky = img[sky_rows].mean()
        return abs(img[far_sea].mean() - sky) / sky

    assert contrast(thick) < contrast(thin) < contrast(clean)


def test_same_seed_same_bytes(dataset, tmp_path):
    code = main(
        [
            "render",
            str(ROOT / "scenes" / "default.yaml"),
            "--vis",
            "300,4000",
            "--res",
            "64x36",
            "--spp",
            "2",
            "--out",
            str(tmp_path),
            "--split",
            "none",  # the command of the dataset fixture, word for word
            "--quiet",
        ]
    )
    assert code == 0
    for rel in [
        "images/clean/default.png",
        "images/v0300/default.png",
        "labels/v0300/default.txt",
        "depth/default.exr",
        "meta/default.json",
        "dataset.json",
    ]:
        digest = [
            hashlib.sha256((root / rel).read_bytes()).hexdigest() for root in (dataset, tmp_path)
        ]
        assert digest[0] == digest[1], rel


def test_preview_writes_a_contact_sheet(dataset, tmp_path):
    out = tmp_path / "sheet.png"
    assert (
        main(
            [
                "preview",
                str(dataset),
                "--levels",
                "clean,v0300",
                "--columns",
                "2",
                "--tile-width",
                "64",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert Image.open(out).size == (128, 36)


PREVIEW_ARGS = ["--levels", "clean,v0300", "--columns", "2", "--tile-width", "64"]


@pytest.mark.parametrize("name", ["sheet.png", "sheet.jpg", "sheet.gif"])
def test_preview_replaces_its_own_sheet_and_never_a_users_file(dataset, tmp_path, capsys, name):
    out = tmp_path / name
    args = ["preview", str(dataset), *PREVIEW_ARGS, "--out", str(out)]
    assert main(args) == 0
    first = out.read_bytes()
    assert main(args) == 0  # its own preview: replaced, with the same bytes
    assert out.read_bytes() == first
    capsys.readouterr()
    # A user's image of the same name and format, a link and a folder are left alone.
    Image.new("RGB", (8, 8), (200, 10, 10)).save(out)
    mine = out.read_bytes()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: a file seahaze did not write" in err and "another name" in err
    assert len(err.strip().splitlines()) == 1 and out.read_bytes() == mine
    target = tmp_path / "elsewhere.png"
    target.write_bytes(b"mine")
    out.unlink()
    out.symlink_to(target)
    assert main(args) == 2 and "a symbolic link" in capsys.readouterr().err
    assert target.read_bytes() == b"mine" and out.is_symlink()
    out.unlink()
    out.mkdir()
    assert main(args) == 2 and "a folder" in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_the_default_preview_goes_beside_the_dataset_and_keeps_a_users_file(
    dataset, tmp_path, capsys
):
    import shutil

    root = tmp_path / "ds"
    shutil.copytree(dataset, root)
    before = sorted(p.relative_to(root) for p in root.rglob("*"))
    assert main(["preview", str(root), *PREVIEW_ARGS]) == 0
    assert Image.open(tmp_path / "ds-preview.png").size == (128, 36)
    assert sorted(p.relative_to(root) for p in root.rglob("*")) == before  # nothing inside
    (tmp_path / "ds-preview.png").write_bytes(b"my notes, not an image")
    assert main(["preview", str(root), *PREVIEW_ARGS]) == 2
    assert (tmp_path / "ds-preview.png").read_bytes() == b"my notes, not an image"
    assert "ds-preview.png: a file seahaze did not write" in capsys.readouterr().err
    other = tmp_path / "mine.png"
    assert main(["preview", str(root), *PREVIEW_ARGS, "--out", str(other)]) == 0
    assert Image.open(other).size == (128, 36)


def test_preview_rejects_unknown_level(dataset, capsys):
    assert main(["preview", str(dataset), "--levels", "v9999"]) == 2
    assert "not in" in capsys.readouterr().err
