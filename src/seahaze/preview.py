"""Contact sheets: a scene's clean image and hazy levels side by side, boxes drawn.

What a user looks at first after a render: ``seahaze preview OUT``. A sequence's sheets animate
as a GIF (Pillow) or an H.264 MP4 (imageio with the ffmpeg binary of the ``imageio-ffmpeg``
wheel: ``pip install 'seahaze[video]'``), chosen by the output file's extension
(:data:`ANIMATION_FORMATS`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from PIL import Image, ImageDraw

from .dataset import Layout
from .fileio import atomic_target
from .visibility import CLEAN_LEVEL

BOX_COLOUR = (255, 210, 0)
CAPTION_HEIGHT_FRACTION = 0.07
ANIMATION_FORMATS = (".gif", ".mp4")
"""File extensions an animated preview may have: the format follows the extension."""
MP4_CRF = 18
"""x264 constant rate factor of an MP4 preview: 18 is visually lossless for most content."""


PREVIEW_MARK = "seahaze preview"
"""Written into every preview file (PNG ``Software`` text, GIF and JPEG comment, MP4 comment
metadata): a later preview overwrites only a file that carries it."""
_MARK_SCAN_BYTES = 1 << 20
"""How much of each end of an MP4 is searched for the mark (ffmpeg writes it in the ``moov``
box, at the end of the file)."""


class PreviewError(ValueError):
    """A dataset folder that cannot be previewed; the message is for the user."""


def written_by_preview(path: Path) -> bool:
    """Whether ``path`` is a plain file a seahaze preview wrote (it carries
    :data:`PREVIEW_MARK`)."""
    if path.is_symlink() or not path.is_file():
        return False
    mark = PREVIEW_MARK.encode()
    if path.suffix.lower() == ".mp4":
        with open(path, "rb") as handle:
            head = handle.read(_MARK_SCAN_BYTES)
            handle.seek(max(path.stat().st_size - _MARK_SCAN_BYTES, 0))
            return mark in head or mark in handle.read()
    try:
        with Image.open(path) as image:
            info = dict(image.info)
    except (OSError, ValueError, Image.DecompressionBombError):
        return False
    values = [info.get("Software"), info.get("comment")]
    return any(v in (PREVIEW_MARK, mark) for v in values)


def check_overwrite(out: Path) -> None:
    """Raise :class:`PreviewError` unless ``out`` is free or a preview seahaze wrote: a user's
    file of the same name is never overwritten (nor a link followed)."""
    if (out.exists() or out.is_symlink()) and not written_by_preview(out):
        what = "a symbolic link" if out.is_symlink() else "a file seahaze did not write"
        if out.is_dir() and not out.is_symlink():
            what = "a folder"
        raise PreviewError(
            f"--out {out}: {what} is there, and a preview never replaces it; "
            "choose another name with --out"
        )


def save_sheet(sheet: Image.Image, out: Path) -> None:
    """Write a contact sheet, marked as a seahaze preview (PNG text chunk, JPEG comment),
    atomically: a failed write leaves any earlier preview whole. The format follows the
    extension (any Pillow writes; one without a mark can be written but never replaced)."""
    from PIL import PngImagePlugin

    suffix = out.suffix.lower()
    options: dict[str, Any] = {}
    if suffix == ".png":
        text = PngImagePlugin.PngInfo()
        text.add_text("Software", PREVIEW_MARK)
        options["pnginfo"] = text
    elif suffix in (".jpg", ".jpeg", ".gif"):
        options["comment"] = PREVIEW_MARK
    image_format = Image.registered_extensions().get(suffix)
    if image_format is None:
        raise PreviewError(f"--out {out}: {suffix or 'no extension'} is not an image format")
    with atomic_target(out) as tmp:
        sheet.save(tmp, format=image_format, **options)


def _manifest(root: Path) -> dict:
    """The dataset's manifest; a :class:`PreviewError` for a missing, foreign or damaged one."""
    from .batch.errors import BatchRefusedError
    from .batch.folder import inspect_folder

    manifest = root / "dataset.json"
    if not manifest.exists():
        raise PreviewError(f"{manifest}: not found; is {root} a seahaze dataset folder?")
    try:
        state = inspect_folder(root)
    except BatchRefusedError as err:
        raise PreviewError(str(err)) from None
    if state.manifest is None:
        raise PreviewError(f"{manifest} is damaged ({state.damaged})")
    return state.manifest


def dataset_levels(root: Path) -> list[str]:
    """Level folder names of a dataset in manifest order, clean first."""
    return [CLEAN_LEVEL, *(level["name"] for level in _manifest(root)["levels"])]


def _read_boxes(
    path: Path, width: int, height: int
) -> list[tuple[int, float, float, float, float]]:
    from .batch.folder import check_label

    problem = check_label(path)
    if problem is not None:
        raise PreviewError(f"{path} {problem}")
    boxes = []
    for line in path.read_text().splitlines():
        cls, cx, cy, w, h = line.split()[:5]
        cx, cy, w, h = float(cx) * width, float(cy) * height, float(w) * width, float(h) * height
        boxes.append((int(cls), cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2))
    return boxes


def _tile(
    layout: Layout, level: str, scene: str, tile_width: int, boxes: bool, names: list[str]
) -> Image.Image:
    path = layout.image(level, scene)
    if not path.exists():
        raise PreviewError(f"{path}: not found")
    try:
        image = Image.open(path).convert("RGB")
    except (OSError, ValueError) as err:  # PIL: truncated, not an image, decompression bomb
        raise PreviewError(f"{path}: cannot read the image ({err})") from None
    scale = tile_width / image.width
    tile = image.resize((tile_width, round(image.height * scale)), Image.LANCZOS)
    draw = ImageDraw.Draw(tile)
    label_path = layout.label(level, scene)
    if boxes and label_path.exists():
        for cls, x0, y0, x1, y1 in _read_boxes(label_path, image.width, image.height):
            draw.rectangle(
                [x0 * scale, y0 * scale, x1 * scale, y1 * scale],
                outline=BOX_COLOUR,
                width=max(1, tile_width // 400),
            )
            draw.text(
                (x0 * scale, y0 * scale - 11),
                names[cls] if cls < len(names) else str(cls),
                fill=BOX_COLOUR,
            )
    caption = "clean" if level == CLEAN_LEVEL else f"V = {int(level[1:])} m"
    bar = round(tile.height * CAPTION_HEIGHT_FRACTION)
    draw.rectangle([0, 0, tile.width, bar], fill=(0, 0, 0))
    draw.text((6, max(0, bar // 2 - 6)), f"{scene}  {caption}", fill=(255, 255, 255))
    return tile


def contact_sheet(
    root: Path,
    scene: str | None = None,
    levels: list[str] | None = None,
    columns: int = 3,
    tile_width: int = 640,
    boxes: bool = True,
) -> Image.Image:
    """A grid of one scene's images (``levels``, default all) with YOLO boxes drawn."""
    layout = Layout(root)
    available = dataset_levels(root)
    levels = levels or available
    unknown = [lv for lv in levels if lv not in available]
    if unknown:
        raise PreviewError(f"level(s) {unknown} not in {root}; available: {', '.join(available)}")
    manifest = _manifest(root)
    scenes = list(manifest["scenes"])
    if not scenes:
        raise PreviewError(f"{root}: no rendered scene yet")
    scene = scene or scenes[0]
    if scene not in scenes:
        raise PreviewError(f"scene '{scene}' not in {root}; available: {', '.join(scenes)}")
    tiles = [
        _tile(layout, level, scene, tile_width, boxes, manifest["classes"]) for level in levels
    ]
    rows = -(-len(tiles) // columns)
    sheet = Image.new("RGB", (columns * tile_width, rows * tiles[0].height), (0, 0, 0))
    for i, tile in enumerate(tiles):
        sheet.paste(tile, ((i % columns) * tile_width, (i // columns) * tiles[0].height))
    return sheet


def sequence_frames(root: Path, sequence: str) -> tuple[list[str], float]:
    """The frame scenes of ``sequence`` in frame order and its frame rate (frames/s)."""
    scenes = _manifest(root)["scenes"]
    frames = sorted(
        (entry["frame"], name)
        for name, entry in scenes.items()
        if isinstance(entry, dict) and entry.get("sequence") == sequence
    )
    if not frames:
        names = sorted({e.get("sequence") for e in scenes.values() if e.get("sequence")})
        raise PreviewError(
            f"sequence '{sequence}' not in {root}; available: {', '.join(names) or 'none'}"
        )
    fps = float(scenes[frames[0][1]]["config"]["sequence"]["fps"])
    return [name for _, name in frames], fps


def animation(
    root: Path,
    sequence: str,
    levels: list[str] | None = None,
    columns: int = 3,
    tile_width: int = 320,
    boxes: bool = True,
) -> tuple[list[Image.Image], float]:
    """One contact sheet per frame of ``sequence`` (its ``levels`` side by side, boxes drawn)
    and the sequence's frame rate (frames/s)."""
    names, fps = sequence_frames(root, sequence)
    sheets = [contact_sheet(root, name, levels, columns, tile_width, boxes) for name in names]
    return sheets, fps


def save_gif(sheets: list[Image.Image], out: Path, fps: float) -> None:
    """Write ``sheets`` as a looping animated GIF at ``fps`` (GIF delays are whole
    hundredths of a second, so the rate is rounded to that)."""
    delay_ms = max(20, round(1000.0 / fps / 10.0) * 10)
    # One adaptive palette per frame: sky and sea gradients band least that way.
    frames = [sheet.convert("P", palette=Image.Palette.ADAPTIVE, colors=255) for sheet in sheets]
    with atomic_target(out) as tmp:
        frames[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=frames[1:],
            duration=delay_ms,
            loop=0,
            disposal=1,
            comment=PREVIEW_MARK,
        )


def save_mp4(sheets: list[Image.Image], out: Path, fps: float) -> None:
    """Write ``sheets`` as an H.264 MP4 (yuv420p, which every player decodes) at ``fps``.

    Sheets of odd width or height get a black column or row so the chroma planes halve
    evenly; one encoder thread, so the same sheets give the same bytes on any machine.
    Raises :class:`PreviewError` when the ``video`` extra is not installed.
    """
    try:
        import imageio.v2 as imageio
        import imageio_ffmpeg  # noqa: F401  (the ffmpeg binary imageio's writer runs)
    except ImportError:
        raise PreviewError(
            f"{out}: an MP4 preview needs imageio and imageio-ffmpeg; "
            "pip install 'seahaze[video]' (or write a .gif)"
        ) from None
    import numpy as np

    with atomic_target(out) as tmp:
        encoded = tmp.with_name(f"{tmp.name}.mp4")  # imageio picks its writer by extension
        try:
            _encode_mp4(imageio, np, sheets, encoded, fps)
            os.replace(encoded, tmp)
        finally:
            encoded.unlink(missing_ok=True)


def _encode_mp4(imageio: Any, np: Any, sheets: list[Image.Image], out: Path, fps: float) -> None:
    """Encode ``sheets`` into the ``.mp4`` file ``out``."""
    width, height = sheets[0].size
    even = (width + width % 2, height + height % 2)
    writer = imageio.get_writer(
        out,
        format="FFMPEG",
        mode="I",
        fps=fps,
        codec="libx264",
        pixelformat="yuv420p",
        quality=None,
        macro_block_size=2,
        ffmpeg_log_level="error",
        ffmpeg_params=[
            *("-crf", str(MP4_CRF), "-threads", "1", "-preset", "medium"),
            *("-metadata", f"comment={PREVIEW_MARK}"),
        ],
    )
    try:
        for sheet in sheets:
            frame = Image.new("RGB", even, (0, 0, 0))
            frame.paste(sheet.convert("RGB"), (0, 0))
            writer.append_data(np.asarray(frame))
    finally:
        writer.close()
