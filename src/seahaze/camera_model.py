"""A camera's character on the PNGs: lens blur and veiling glare, sensor noise, JPEG compression.

Rendered images are those of a perfect camera: no blur beyond the pixel, no noise beyond the
renderer's, no compression. ``render.camera_model`` (:class:`seahaze.spec.CameraModelSpec`)
gives the PNGs a real camera's, the same way for the clean image and every level, in this order:

1. **Exposure.** The radiance times the scene's exposure (:mod:`seahaze.imaging`): linear
   display values, 1 at the PNG's white, not clipped. With ``shutter_s`` a sequence frame is
   then integrated over its exposure time: each pixel averaged along its image displacement
   during it, the camera's own motion and the vessels' (:mod:`seahaze.motion_blur`; a global
   shutter, no rolling-shutter skew).
2. **Optics** (:func:`blur`), in linear light and before any clip, so a sun glint spreads as
   much light as a lens would spread from it: a point spread function
   ``(1 − h)·G(σ_core) + h·G(σ_halo)``. The core stands for the lens's blur: the best Gaussian
   fit to an Airy pattern has ``σ = 0.42·λ·N`` (Zhang, Zerubia & Olivo-Marin, "Gaussian
   approximations of fluorescence microscope point-spread function models", Applied Optics
   46(10):1819, 2007; ``σ = 0.21·λ/NA`` with ``NA = 1/(2N)``), 0.54 px at f/8 for 550 nm and
   3.45 µm pixels, and aberrations and focus widen it. The halo is veiling glare, the light
   that lens surfaces, barrel and housing window scatter over the whole frame (ISO 9358:1994;
   Talvala et al., "Veiling glare in high dynamic range imaging", ACM TOG 26(3), 2007, measure
   its spread function): a share ``h`` of every pixel's light in a wide Gaussian, a smooth
   stand-in for the measured power-law tails. Each ``G`` is Lindeberg's discrete Gaussian
   (Lindeberg, "Scale-space for discrete signals", IEEE TPAMI 12(3):234, 1990), whose
   transfer function is ``exp(σ²(cos ω − 1))`` per axis: it sums to 1 and its second moment
   is exactly ``σ²`` at every σ, also below a pixel, where a sampled Gaussian's is not. The
   convolution is done in the DCT-II domain, which is convolution with the image mirrored at
   its edges (Martucci, "Symmetric convolution and the discrete sine and cosine transforms",
   IEEE Trans. Signal Processing 42(5):1038, 1994): no light is lost at the frame's edge and
   a flat field stays flat.
3. **Sensor** (:func:`sensor_signal`). A pixel holding the linear value ``x`` collects
   ``S = min(x, 1)·full_well_e`` electrons; the read-out adds shot noise (Poisson, variance
   ``S``) and read noise (``read_noise_e`` RMS), the EMVA 1288 linear camera model, whose
   variance in electrons is ``S + r²``. Both are drawn as one Gaussian of that variance per
   pixel and channel (shot noise's normal approximation: its variance exact, its skew ignored,
   which at the ≥ 100 electrons of every pixel brighter than 1 % of white is below 0.1), no
   demosaicing (every channel is a pixel of its own). A pixel at or above the full well reads
   white without noise, as a saturated pixel does.
4. **White balance** (``white_balance: illuminant``): the channels scaled by ``E_G/E_c``, ``E``
   the horizontal irradiance of the scene's sun and sky (linear sRGB), after the sensor, as a
   camera's processing does (von Kries' diagonal adaptation: Fairchild, *Color Appearance
   Models*, 3rd ed., Wiley 2013, ch. 9). Daylight off D65 — a 28° sun through turbidity 3 is
   about 10 % red-heavy — then leaves a white surface grey, as in a photograph, instead of
   the warm cast the raw renderer shows; the gains are in ``meta``.
5. **Encoding**: the 8-bit sRGB codes of :func:`seahaze.imaging.to_srgb8`, dithered as
   ``render.dither`` says.
6. **Compression** (:func:`jpeg_round_trip`), with ``jpeg_quality``: Pillow's JPEG encoder at
   that quality (4:2:0 chroma, baseline), decoded back, so the files stay PNG.

The noise is seeded by :func:`seahaze.seeds.camera_noise_seed` from the scene's seed and name,
not the level: the clean image and every level share one noise realisation per pixel (common
random numbers), so two levels of a scene differ by their haze, not by their noise. The
normals come from the raw PCG64 stream through the Box–Muller transform (numpy guarantees its
bit generators' streams, not its distributions'), so the same config and seed give the same
bytes. Sequences: every frame is a scene of its own name, so the noise changes frame to frame
as a real camera's does.

Not modelled: a rolling shutter, dark current and fixed-pattern noise (PRNU, DSNU), the colour
filter array and demosaicing, lens distortion and vignetting, the camera's own tone curve.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import numpy as np
import scipy.fft
from PIL import Image, features

from . import imaging
from .motion_blur import blur_along_motion
from .seeds import camera_noise_seed
from .spec import CameraModelSpec

MAX_LINEAR = 1.0e6
"""Largest exposed value the blur takes (1 is the PNG's white): the sun's disc is about 10^5,
and a value of float32's range would swamp the transform's rounding for the whole image."""
JPEG_SUBSAMPLING = "4:2:0"
"""Chroma subsampling of the JPEG option: what cameras and Pillow's default use."""
APPLIED_TO = "clean and every level PNG; EXRs linear, without it"


def discrete_gaussian_transfer(sigma_px: float, size: int) -> np.ndarray:
    """The transfer function ``exp(σ²(cos ω − 1))`` of Lindeberg's discrete Gaussian of
    standard deviation ``sigma_px`` at the frequencies ``ω = πk/size`` of a DCT-II of ``size``
    samples (k = 0 … size − 1)."""
    omega = np.pi * np.arange(size) / size
    return np.exp(sigma_px**2 * (np.cos(omega) - 1.0))


def psf_transfer(shape: tuple[int, int], settings: CameraModelSpec) -> np.ndarray:
    """The point spread function's (height, width) DCT-II multipliers: the Gaussian core and,
    with ``halo_fraction``, the veiling-glare halo, weighted by their shares of the light."""
    height, width = shape

    def gaussian(sigma: float) -> np.ndarray:
        rows = discrete_gaussian_transfer(sigma, height)
        cols = discrete_gaussian_transfer(sigma, width)
        return rows[:, None] * cols[None, :]

    halo = settings.halo_fraction
    transfer = (1.0 - halo) * gaussian(settings.psf_sigma_px)
    if halo > 0.0:
        transfer += halo * gaussian(settings.halo_sigma_px)
    return transfer


def has_blur(settings: CameraModelSpec) -> bool:
    """Whether the settings blur at all (a core wider than 0 or a halo)."""
    return settings.psf_sigma_px > 0.0 or settings.halo_fraction > 0.0


def finite_light(linear: np.ndarray) -> np.ndarray:
    """``linear`` as float64 with NaN as black and values limited to [0, :data:`MAX_LINEAR`]:
    what the blurs take, since one bad pixel would otherwise spread over the whole image."""
    values = np.nan_to_num(np.asarray(linear, dtype=np.float64), nan=0.0, posinf=MAX_LINEAR)
    return np.clip(values, 0.0, MAX_LINEAR, out=values)


def blur(linear: np.ndarray, settings: CameraModelSpec) -> np.ndarray:
    """``linear`` (H, W, 3) convolved with the point spread function of ``settings``, mirrored
    at the frame's edges (module docstring, step 2); float64, its values
    :func:`finite_light` first."""
    values = finite_light(linear)
    if not has_blur(settings):
        return values
    coefficients = scipy.fft.dctn(values, type=2, axes=(0, 1), norm="ortho")
    coefficients *= psf_transfer(values.shape[:2], settings)[..., None]
    return scipy.fft.idctn(coefficients, type=2, axes=(0, 1), norm="ortho")


def standard_normals(seed: np.random.SeedSequence, count: int) -> np.ndarray:
    """``count`` standard normal values of ``seed`` by the Box–Muller transform of its raw
    PCG64 stream: two 53-bit uniforms in (0, 1) per pair of normals, the same values on every
    platform and numpy version up to the last bits of ``log``, ``cos`` and ``sin``."""
    pairs = (count + 1) // 2
    words = np.random.PCG64(seed).random_raw(2 * pairs)
    uniform = ((words >> np.uint64(11)).astype(np.float64) + 0.5) * 2.0**-53
    radius = np.sqrt(-2.0 * np.log(uniform[0::2]))
    angle = 2.0 * np.pi * uniform[1::2]
    normals = np.empty(2 * pairs)
    normals[0::2] = radius * np.cos(angle)
    normals[1::2] = radius * np.sin(angle)
    return normals[:count]


def sensor_signal(
    linear: np.ndarray, full_well_e: float, read_noise_e: float, normals: np.ndarray
) -> np.ndarray:
    """The linear values (1 = white) a sensor reads for exposed values ``linear``: ``S =
    min(x, 1)·full_well_e`` electrons plus ``normals`` (one per value) times the shot and read
    noise ``sqrt(S + read_noise_e²)``, divided by the full well; saturated pixels (x ≥ 1) read
    1. The variance in these units is ``x/full_well_e + (read_noise_e/full_well_e)²``."""
    values = np.asarray(linear, dtype=np.float64)
    electrons = np.clip(values, 0.0, 1.0) * full_well_e
    noisy = electrons + normals.reshape(values.shape) * np.sqrt(electrons + read_noise_e**2)
    signal = noisy / full_well_e
    signal[values >= 1.0] = 1.0
    return signal


def jpeg_round_trip(codes: np.ndarray, quality: int) -> np.ndarray:
    """8-bit RGB ``codes`` encoded by Pillow's JPEG encoder at ``quality`` (baseline,
    :data:`JPEG_SUBSAMPLING` chroma) and decoded back: the pixels a JPEG camera would store."""
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(codes, dtype=np.uint8)).save(
        buffer, format="JPEG", quality=quality, subsampling=JPEG_SUBSAMPLING, optimize=False
    )
    buffer.seek(0)
    with Image.open(buffer) as decoded:
        return np.asarray(decoded.convert("RGB")).copy()


def capture(
    radiance: np.ndarray,
    exposure: float,
    settings: CameraModelSpec,
    noise: np.random.SeedSequence,
    dither: np.random.SeedSequence | None = None,
    gains: list[float] | None = None,
    motion_px: np.ndarray | None = None,
) -> np.ndarray:
    """The 8-bit sRGB image (H, W, 3) the camera of ``settings`` makes of ``radiance``: exposed,
    blurred by each pixel's displacement ``motion_px`` over the shutter time (None: an
    instant; :mod:`seahaze.motion_blur`) and by the lens, read with the sensor noise of seed
    ``noise``, white-balanced by the channel ``gains`` (None: none), encoded (dithered with
    ``dither``) and, with ``jpeg_quality``, JPEG-compressed (module docstring, steps 1–6)."""
    exposed = np.asarray(radiance, dtype=np.float64) * float(exposure)
    if motion_px is not None:
        exposed = blur_along_motion(finite_light(exposed), motion_px)
    linear = blur(exposed, settings)
    if settings.full_well_e is not None:
        normals = standard_normals(noise, linear.size)
        linear = sensor_signal(linear, settings.full_well_e, settings.read_noise_e, normals)
    if gains is not None:
        linear = linear * np.asarray(gains, np.float64)
    codes = imaging.to_srgb8(linear.astype(np.float32), 1.0, dither)
    if settings.jpeg_quality is not None:
        codes = jpeg_round_trip(codes, settings.jpeg_quality)
    return codes


def white_balance_gains(illuminant_rgb: np.ndarray) -> list[float]:
    """The channel gains ``E_G/E_c`` that make light of colour ``illuminant_rgb`` (linear sRGB)
    grey, green kept (module docstring, step 4)."""
    e = np.asarray(illuminant_rgb, np.float64)
    if e.shape != (3,) or not np.all(e > 0.0):
        raise ValueError(f"an illuminant needs three positive channels, got {e}")
    return [float(e[1] / c) for c in e]


def camera_model_meta(
    settings: CameraModelSpec | None, seed: int, illuminant_rgb: np.ndarray | None = None
) -> dict[str, Any]:
    """``meta``'s record of the camera model (in its ``render`` entry): nothing without one (a
    scene's meta stays what it was before the camera model), else ``camera_model``, every
    setting, the seed of :func:`seahaze.seeds.camera_noise_seed`, with white balance its gains
    (from ``illuminant_rgb``, the scene's light on a level surface) and, with JPEG, the codec."""
    if settings is None:
        return {}
    record: dict[str, Any] = settings.model_dump(mode="json")
    record["noise_seed"] = seed
    if settings.white_balance == "illuminant":
        if illuminant_rgb is None:
            raise ValueError("white balance to the illuminant needs the scene's light")
        record["white_balance_gains"] = white_balance_gains(illuminant_rgb)
    if settings.jpeg_quality is not None:
        record["jpeg_codec"] = jpeg_codec()
    record["applied_to"] = APPLIED_TO
    return {"camera_model": record}


def jpeg_codec() -> str:
    """Pillow's JPEG library and version: the JPEG option's bytes depend on its encoder."""
    turbo = features.version("libjpeg_turbo")
    library = f"libjpeg-turbo {turbo}" if turbo else f"libjpeg {features.version('jpg')}"
    return f"Pillow {Image.__version__}, {library}"


def settings_from_meta(render_meta: Mapping[str, Any]) -> CameraModelSpec | None:
    """The camera model ``meta``'s ``render`` record gives (:func:`camera_model_meta`), or None
    when it has none (a scene without a camera model, or rendered before it existed)."""
    record = render_meta.get("camera_model")
    if record is None:
        return None
    fields = CameraModelSpec.model_fields
    return CameraModelSpec.model_validate({k: v for k, v in record.items() if k in fields})


def png_pixels(
    radiance: np.ndarray,
    exposure: float,
    render_meta: Mapping[str, Any],
    scene: str,
    level: str,
    motion_px: np.ndarray | None = None,
) -> np.ndarray:
    """The pixels of the PNG of image ``level`` of ``scene``, as ``meta``'s ``render`` record
    says: the camera model's (:func:`capture`, with the frame's ``motion_px`` over its
    shutter time) when it has one, else :func:`seahaze.imaging.to_srgb8`, dithered either way
    as the record says."""
    dither = imaging.png_dither(render_meta, scene, level)
    settings = settings_from_meta(render_meta)
    if settings is None:
        return imaging.to_srgb8(radiance, exposure, dither)
    record = render_meta["camera_model"]
    noise = camera_noise_seed(int(record["noise_seed"]), scene)
    gains = record.get("white_balance_gains")
    return capture(radiance, exposure, settings, noise, dither, gains, motion_px)
