"""The scene specification: what a scene YAML may say, validated before any geometry exists.

Every field carries its type, unit, default and allowed range here and nowhere else;
``docs/scenes.md`` is generated from these models (``scripts/gen_scene_docs.py``) so it cannot
drift. Angles are degrees, distances metres, world frame Z up with the camera above the origin.
Azimuths and headings are measured counter-clockwise from +x when seen from above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Literal, get_args

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)
from pydantic.fields import FieldInfo

from .visibility import (
    GRADED_LEVELS_M,
    MAX_LEVEL_M,
    MAX_LEVELS,
    MIN_LEVEL_M,
    ExtinctionSpectrum,
    Threshold,
    level_name_clash,
)

BOUND_KINDS = ("ge", "gt", "le", "lt")
"""The numeric constraints a field may carry, as pydantic names them."""
MAX_PLACED_VESSELS = 200
"""Most explicit vessels per scene: each is a mesh in the render and a box to label
(docs/limits.md); 3000 buoys validated in 3 s and then rendered for minutes."""


def model_in(annotation: Any) -> type[BaseModel] | None:
    """The spec model inside an annotation such as ``Model | None`` or ``list[Model]``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = model_in(arg)
        if found is not None:
            return found
    return None


def field_bounds(info: FieldInfo) -> list[tuple[str, Any]]:
    """The ``(kind, value)`` numeric bounds of a field, kind one of :data:`BOUND_KINDS`."""
    return [
        (kind, getattr(meta, kind))
        for meta in info.metadata
        for kind in BOUND_KINDS
        if getattr(meta, kind, None) is not None
    ]


SEA_TIME_LIMIT_S = 1.0e6
"""Latest sea time (s) a scene or a sequence's last frame may show: beyond about 11.6 days the
wave phases ω·t lose their float precision."""


def _unit(unit: str) -> dict[str, str]:
    return {"unit": unit}


class _Spec(BaseModel):
    """Base of every spec section: unknown keys (typos) are errors, values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)

    @field_validator("*", mode="before")
    @classmethod
    def _numbers_are_not_booleans(cls, value: Any, info: ValidationInfo) -> Any:
        # YAML's true/false would otherwise pass as 1/0 where a number is asked for
        # (`sequence.frames: true` rendered one frame).
        if isinstance(value, bool) and info.field_name is not None:
            annotation = cls.model_fields[info.field_name].annotation
            kinds = set(get_args(annotation)) or {annotation}
            if bool not in kinds and kinds & {int, float}:
                raise ValueError("a number is needed here, not true/false")
        return value


class CameraSpec(_Spec):
    """A pinhole camera above the sea at the world origin."""

    height_m: float = Field(
        12.0,
        ge=0.5,
        le=1000.0,
        description="Height of the camera above mean sea level.",
        json_schema_extra=_unit("m"),
    )
    fov_deg: float = Field(
        60.0,
        gt=1.0,
        le=120.0,
        description="Horizontal field of view.",
        json_schema_extra=_unit("deg"),
    )
    pitch_deg: float = Field(
        -1.5,
        ge=-60.0,
        le=30.0,
        description="Elevation of the optical axis; negative looks down at the sea.",
        json_schema_extra=_unit("deg"),
    )
    heading_deg: float = Field(
        0.0,
        ge=-360.0,
        le=360.0,
        description="Azimuth of the optical axis, counter-clockwise from +x.",
        json_schema_extra=_unit("deg"),
    )
    resolution: tuple[
        Annotated[int, Field(ge=8, le=8192)], Annotated[int, Field(ge=8, le=8192)]
    ] = Field(
        (1280, 720),
        description="Image width and height in pixels (`--res WxH` overrides).",
        json_schema_extra=_unit("px"),
    )
    roll_deg: float = Field(
        0.0,
        ge=-45.0,
        le=45.0,
        description="Roll about the optical axis; positive turns the camera clockwise as seen "
        "from behind it (its right side down, like a ship's port-up roll), so the horizon "
        "rises to the right of the image, its slope `tan(roll)`. Recorded only when not 0.",
        json_schema_extra=_unit("deg"),
    )

    @model_serializer(mode="wrap")
    def _omit_level(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A level camera's recorded config and meta stay byte-identical to before roll existed.
        data = handler(self)
        if self.roll_deg == 0.0:
            data.pop("roll_deg", None)
        return data


TWILIGHT_SUN_DEG = (-6.0, 0.0)
"""Sun elevations of a `twilight` sky (deg): from sunset to the end of civil twilight."""
DAYLIGHT_SUN_DEG = (0.5, 89.5)
"""Sun elevations of the daylight skies (deg), where the Hosek–Wilkie model holds."""


class SunSpec(_Spec):
    """The sun: the Hosek–Wilkie sun-and-sky model's by day, set below the horizon under a
    `twilight` sky."""

    elevation_deg: float = Field(
        25.0,
        ge=TWILIGHT_SUN_DEG[0],
        le=DAYLIGHT_SUN_DEG[1],
        description="Sun elevation above the horizon: 0.5..89.5 under a clear, broken or "
        "overcast sky; -6..0 (the sun set, civil twilight) under a `twilight` sky.",
        json_schema_extra=_unit("deg"),
    )
    azimuth_deg: float = Field(
        140.0,
        ge=-360.0,
        le=360.0,
        description="Sun azimuth, counter-clockwise from +x (0 = in front of a camera with "
        "heading 0).",
        json_schema_extra=_unit("deg"),
    )
    scale: float = Field(
        1.0,
        ge=0.0,
        le=100.0,
        description="Multiplier on the sun's radiance (1 = physical).",
        json_schema_extra=_unit("1"),
    )


class CloudSpec(_Spec):
    """A broken cloud layer (seahaze.clouds): flat cumulus at a base height, covering `oktas`
    eighths of the sky, seeded by the scene's seed."""

    oktas: int = Field(
        5,
        ge=1,
        le=7,
        description="Cloud amount in eighths of the sky (WMO): 1-2 few, 3-4 scattered, 5-7 "
        "broken; 8 is `sky.model: overcast`.",
        json_schema_extra=_unit("okta"),
    )
    base_height_m: float = Field(
        1000.0,
        ge=100.0,
        le=6000.0,
        description="Height of the cloud base above the sea; must be above `haze.top_m`.",
        json_schema_extra=_unit("m"),
    )
    size_m: float = Field(
        1000.0,
        ge=100.0,
        le=20000.0,
        description="Scale of the largest clouds (the lattice spacing of the noise's largest "
        "octave; smaller ones go down to a sixteenth of it).",
        json_schema_extra=_unit("m"),
    )
    seed: int | None = Field(
        None, ge=0, description="Seed of the cloud layer; default derived from `render.seed`."
    )


class SkySpec(_Spec):
    """The sky above the haze layer: clear (Hosek & Wilkie 2012, Mitsuba `sunsky`), broken
    cloud (seahaze.clouds), overcast (the CIE overcast sky, :mod:`seahaze.overcast`) or the
    clear sky after sunset (:mod:`seahaze.twilight`)."""

    model: Literal["clear", "broken", "overcast", "twilight"] = Field(
        "clear",
        description="`clear`: the Hosek–Wilkie sun and sky. `broken`: the clear sky with a "
        "layer of cloud (`clouds`) that hides the sun when one lies in its direction; the "
        "clouds are grey, as bright as Kasten & Czeplak's (1980) irradiance under that "
        "amount of cloud asks. `overcast`: a full cloud deck "
        "hides the sun; the CIE overcast sky (radiance a third of the zenith's at the "
        "horizon, grey), as bright as the quarter of the clear sky's global irradiance at "
        "the same sun elevation and turbidity that cloud lets through (Kasten & Czeplak "
        "1980). The sun's elevation still sets how bright the day is. `twilight`: the clear "
        "sky after sunset (`sun.elevation_deg` -6..0), sunlight scattered in the air above "
        "the Earth's shadow (seahaze.twilight), no sun.",
    )
    clouds: CloudSpec | None = Field(
        None,
        description="The cloud layer of a `broken` sky (default: its defaults); only with "
        "`model: broken`.",
    )
    turbidity: float = Field(
        3.0,
        ge=1.0,
        le=10.0,
        description="Linke turbidity of the atmosphere above the haze (2 arctic, 3 clear, 6 "
        "humid, 10 hazy).",
        json_schema_extra=_unit("1"),
    )
    ground_albedo: float = Field(
        0.06,
        ge=0.0,
        le=1.0,
        description="Ground (sea) albedo used by the sky model's lower hemisphere.",
        json_schema_extra=_unit("1"),
    )
    scale: float = Field(
        1.0,
        ge=0.0,
        le=100.0,
        description="Multiplier on the sky's radiance (1 = physical).",
        json_schema_extra=_unit("1"),
    )

    @model_serializer(mode="wrap")
    def _omit_the_clear_model(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A clear sky keeps a recorded config byte-identical to before the overcast sky existed
        # (the config's digest decides whether a dataset folder resumes).
        data = handler(self)
        if self.model == "clear":
            data.pop("model", None)
        if self.clouds is None:
            data.pop("clouds", None)
        return data

    @model_validator(mode="after")
    def _clouds_only_when_broken(self) -> SkySpec:
        if self.clouds is not None and self.model != "broken":
            raise ValueError(
                f"clouds: only a `broken` sky has a cloud layer (model is '{self.model}'); "
                "set model: broken or remove clouds"
            )
        return self

    @property
    def cloud_layer(self) -> CloudSpec:
        """The cloud layer of a broken sky: `clouds`, or its defaults."""
        return self.clouds if self.clouds is not None else CloudSpec()


class SeaSpec(_Spec):
    """The sea surface: geometry from a sea state, optics of a Fresnel interface over dark water."""

    model: Literal["flat", "gerstner", "fft"] = Field(
        "fft",
        description="Surface generator: `flat` plane, `gerstner` wave sum or Tessendorf `fft` "
        "height field.",
    )
    spectrum: Literal["jonswap", "pierson_moskowitz", "phillips"] = Field(
        "jonswap", description="Wave spectrum the generator samples."
    )
    wind_speed: float = Field(
        6.0,
        ge=0.0,
        le=40.0,
        description="Wind speed 10 m above the sea; sets the spectrum and the Cox–Munk roughness.",
        json_schema_extra=_unit("m/s"),
    )
    beaufort: int | None = Field(
        None,
        ge=0,
        le=12,
        description="Beaufort force; when given it sets `wind_speed` from the WMO table.",
        json_schema_extra=_unit("Bft"),
    )
    fetch_km: float = Field(
        100.0,
        gt=0.0,
        le=5000.0,
        description="Fetch for the JONSWAP spectrum.",
        json_schema_extra=_unit("km"),
    )
    direction_deg: float = Field(
        30.0,
        ge=-360.0,
        le=360.0,
        description="Direction the waves travel toward, counter-clockwise from +x.",
        json_schema_extra=_unit("deg"),
    )
    choppiness: float = Field(
        0.8,
        ge=0.0,
        le=2.0,
        description="Horizontal (choppy) displacement factor of the FFT and Gerstner surfaces.",
        json_schema_extra=_unit("1"),
    )
    time_s: float = Field(
        0.0,
        ge=0.0,
        le=SEA_TIME_LIMIT_S,
        description="Time of the wave field; sequences advance it consistently (at most about "
        "11.6 days: the wave phases ω·t keep their precision).",
        json_schema_extra=_unit("s"),
    )
    seed: int | None = Field(
        None, ge=0, description="Seed of the wave phases; default derived from `render.seed`."
    )
    quality: Literal["low", "medium", "high"] = Field(
        "medium", description="Mesh density to the horizon (about 0.1M, 0.5M, 2M triangles)."
    )
    ior: float = Field(
        1.333,
        ge=1.0,
        le=2.0,
        description="Refractive index of sea water.",
        json_schema_extra=_unit("1"),
    )
    water_color: tuple[
        Annotated[float, Field(ge=0.0, le=1.0)],
        Annotated[float, Field(ge=0.0, le=1.0)],
        Annotated[float, Field(ge=0.0, le=1.0)],
    ] = Field(
        (0.004, 0.016, 0.020),
        description="Diffuse reflectance of the water body below the interface (linear RGB).",
        json_schema_extra=_unit("1"),
    )
    roughness: float | None = Field(
        None,
        ge=0.001,
        le=1.0,
        description="Microfacet roughness (alpha) of the whole sea; default from the wind by "
        "Cox–Munk, less the slopes the mesh resolves near the camera (docs/ocean.md).",
        json_schema_extra=_unit("1"),
    )
    whitecaps: bool = Field(
        True,
        description="Whitecaps on the breaking crests, covering the fraction of the sea the "
        "wind's coverage law gives (3.9 % at 15 m/s; none on a `flat` sea), and from force 7 "
        "(13.9 m/s) the foam streaks the wind draws along its direction (seahaze.ocean.streaks).",
    )


AxisName = Literal["+x", "-x", "+y", "-y", "+z", "-z"]
"""A signed axis of a mesh file's own frame."""


class UserMeshSpec(_Spec):
    """A vessel mesh file used instead of the class's procedural model.

    The mesh is rotated so `forward_axis` points to the bow and `up_axis` up, scaled to the
    length `scale_m`, centred on midships and sunk to its draft (rules in `assets/README.md`).
    Its boxes get the YOLO id of the placed vessel's `class`. Each material keeps its colour;
    its roughness is rounded to the nearest of the built-in vessels' roughness values (0.15,
    0.3, 0.35 … 0.85), which keeps every scene on one compiled kernel.
    """

    path: str = Field(
        min_length=1,
        max_length=4096,
        description="Mesh file (.obj .ply .glb .gltf .stl): absolute, relative to the scene "
        "file's folder, or relative to the repository's `assets/` folder.",
    )
    scale_m: float = Field(
        gt=0.0,
        le=500.0,
        description="Overall length after scaling, along `forward_axis` (a length, not a "
        "factor: the file's units do not matter).",
        json_schema_extra=_unit("m"),
    )
    up_axis: AxisName = Field("+z", description="The file's up axis (glTF exports: `+y`).")
    forward_axis: AxisName = Field(
        "+x", description="The file's bow direction, perpendicular to `up_axis`."
    )
    draft_m: float | None = Field(
        None,
        ge=0.0,
        le=50.0,
        description="Depth of the lowest point below the waterline, less than the scaled "
        "height (a mesh sunk whole could be neither seen nor labelled); default 10 % of the "
        "scaled height.",
        json_schema_extra=_unit("m"),
    )

    @model_validator(mode="after")
    def _perpendicular_axes(self) -> UserMeshSpec:
        if self.up_axis[1] == self.forward_axis[1]:
            raise ValueError(
                f"up_axis {self.up_axis} and forward_axis {self.forward_axis} must be "
                "perpendicular (different letters)"
            )
        return self


class PlacedVessel(_Spec):
    """One vessel at an explicit place relative to the camera."""

    kind: str = Field(
        alias="class",
        description="Vessel class, one of the library's classes (see `seahaze classes`); "
        "with `mesh`, the class the mesh is labelled as.",
    )
    distance_m: float = Field(
        gt=10.0,
        le=50000.0,
        description="Horizontal distance from the camera to midships.",
        json_schema_extra=_unit("m"),
    )
    bearing_deg: float = Field(
        0.0,
        ge=-180.0,
        le=180.0,
        description="Bearing from the camera's heading, positive to the left.",
        json_schema_extra=_unit("deg"),
    )
    heading_deg: float = Field(
        90.0,
        ge=-360.0,
        le=360.0,
        description="Direction the bow points, counter-clockwise from +x.",
        json_schema_extra=_unit("deg"),
    )
    length_m: float | None = Field(
        None,
        gt=1.0,
        le=500.0,
        description="Length overall; default sampled in the class's range (not with `mesh`, "
        "whose length is `mesh.scale_m`).",
        json_schema_extra=_unit("m"),
    )
    mesh: UserMeshSpec | None = Field(
        None, description="A user mesh file instead of the procedural model of the class."
    )
    speed_kn: float | None = Field(
        None,
        ge=0.0,
        le=40.0,
        description="Speed through the water, at most the top of the class's service-speed "
        "range (docs/ocean.md); a moving vessel has a wake. Default 0: stopped, moored or "
        "drifting (sampled vessels get speeds drawn in their class's range).",
        json_schema_extra=_unit("kn"),
    )

    turn_rate_deg_s: float | None = Field(
        None,
        ge=-10.0,
        le=10.0,
        description="Rate of turn in a `sequence`, counter-clockwise positive (a ship turns at "
        "most a few degrees per second). Default: a straight course.",
        json_schema_extra=_unit("deg/s"),
    )

    @model_serializer(mode="wrap")
    def _omit_unset_turn(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A still scene's recorded config stays as it was before sequences existed.
        data = handler(self)
        if self.turn_rate_deg_s is None:
            data.pop("turn_rate_deg_s", None)
        return data

    @model_validator(mode="after")
    def _one_length(self) -> PlacedVessel:
        if self.mesh is not None and self.length_m is not None:
            raise ValueError(
                "length_m does not apply to a user mesh: give its length as mesh.scale_m"
            )
        return self


class DetectableSpec(_Spec):
    """A share of the sampled vessels placed near enough to look at least so tall."""

    min_height_mrad: float = Field(
        14.4,
        gt=0.0,
        le=500.0,
        description="Least angular height above the waterline (the top of the label's box): "
        "14.4 mrad is 16 px at 1280×720 and a 60° field of view (the focal length in pixels "
        "is width / (2 tan(fov/2)), so 8 px at 640×360). An angle, so a layout is the same "
        "at every `--res`. Each class's least height per length "
        "(`seahaze.vessels.library.MIN_AIR_DRAFT_RATIO`) caps such a vessel's distance.",
        json_schema_extra=_unit("mrad"),
    )
    share: float = Field(
        0.5,
        ge=0.0,
        le=1.0,
        description="Share of `count` (rounded up) placed so; the rest anywhere in `distance_m`.",
        json_schema_extra=_unit("1"),
    )


class VesselSampler(_Spec):
    """Vessels drawn at random along the view depth, each at a speed drawn in its class's
    service-speed range (buoys moored)."""

    count: int = Field(5, ge=0, le=100, description="Number of vessels.")
    classes: dict[str, Annotated[float, Field(gt=0.0, le=1.0e6)]] | None = Field(
        None, description="Class mix as relative weights; default all classes equally."
    )
    distance_m: tuple[Annotated[float, Field(gt=10.0)], Annotated[float, Field(le=50000.0)]] = (
        Field(
            (150.0, 4000.0),
            description="Range of horizontal distances from the camera.",
            json_schema_extra=_unit("m"),
        )
    )
    distribution: Literal["log", "uniform"] = Field(
        "log",
        description="Near-to-far distance law: `log` spreads vessels evenly in log-distance "
        "(as many near as far in each octave).",
    )
    bearing_spread_deg: float | None = Field(
        None,
        ge=0.0,
        le=180.0,
        description="Half-width of the bearing range; default keeps vessels inside the field "
        "of view.",
        json_schema_extra=_unit("deg"),
    )
    min_separation_m: float = Field(
        40.0,
        ge=0.0,
        le=5000.0,
        description="Minimum clearance between hull footprints.",
        json_schema_extra=_unit("m"),
    )
    max_image_overlap: float | None = Field(
        None,
        ge=0.0,
        le=1.0,
        description="Most a vessel may overlap another in the image: the share of the narrower "
        "one's bearing interval (the angles its footprint spans, seen from the camera) that "
        "the two share; 0 keeps them side by side, as traffic seen from a ship mostly is. "
        "Default: no such rule (vessels apart on the water may still hide each other).",
        json_schema_extra=_unit("1"),
    )
    detectable: DetectableSpec | None = Field(
        None,
        description="Place a share of the vessels near enough to look at least so tall "
        "(default: distances drawn over the whole range, however small a vessel looks).",
    )
    seed: int | None = Field(
        None, ge=0, description="Seed of the layout; default derived from `render.seed`."
    )

    @model_serializer(mode="wrap")
    def _omit_unset_rules(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # Without these rules a recorded config stays byte-identical to before they existed.
        data = handler(self)
        for key in ("max_image_overlap", "detectable"):
            if getattr(self, key) is None:
                data.pop(key, None)
        return data

    @model_validator(mode="after")
    def _ordered_range(self) -> VesselSampler:
        lo, hi = self.distance_m
        if lo >= hi:
            raise ValueError(
                f"distance_m must be [near, far] with near < far, got [{lo:g}, {hi:g}]"
            )
        return self


class VesselsSpec(_Spec):
    """Vessels in the scene: an explicit list, a sampler, or both."""

    placed: list[PlacedVessel] = Field(
        default_factory=list,
        max_length=MAX_PLACED_VESSELS,
        description=f"Vessels at explicit places (at most {MAX_PLACED_VESSELS}).",
    )
    sample: VesselSampler | None = Field(
        None, description="Vessels drawn at random (added to `placed`)."
    )
    follow_slope: bool = Field(
        False,
        description="Pitch and roll every vessel to the sea slope across its length and beam "
        "(a long ship bridges short waves); default upright, heaving only.",
    )
    wakes: bool = Field(
        True,
        description="Moving vessels make their Kelvin waves, bow wave and white foam wake in "
        "the sea.",
    )


class FogLayerSpec(_Spec):
    """A layer of sea fog under thinner haze (seahaze.fog_layer): dense from the sea up to its
    top, then thinning over a soft edge to `above_ratio` of its density up to `haze.top_m`. A
    level's extinction (3.912/V) is the extinction along the horizontal line of sight at the
    camera's height: a camera above the fog sees the thin haze at V, the fog below denser."""

    top_m: float = Field(
        ...,
        ge=20.0,
        le=400.0,
        description="Height of the fog top (the inversion) above sea level.",
        json_schema_extra=_unit("m"),
    )
    edge_m: float = Field(
        10.0,
        ge=1.0,
        le=100.0,
        description="Thickness scale of the fog's top edge: within 2 edge_m of the top the "
        "density goes 88 % of the way from the fog's to the haze's above.",
        json_schema_extra=_unit("m"),
    )
    above_ratio: float = Field(
        0.1,
        ge=0.01,
        le=1.0,
        description="Density of the haze above the fog relative to the fog's.",
        json_schema_extra=_unit("1"),
    )


class PatchesSpec(_Spec):
    """Patches of denser and thinner fog (seahaze.haze_field): fractal noise stretched along
    the drift direction modulating the density, seeded by the scene's seed."""

    correlation_m: float = Field(
        300.0,
        ge=20.0,
        le=2000.0,
        description="Correlation length of the patches along the drift direction (`drift`).",
        json_schema_extra=_unit("m"),
    )
    anisotropy: float = Field(
        3.0,
        ge=1.0,
        le=10.0,
        description="How many times shorter the patches are across the drift direction than "
        "along it (1: round).",
        json_schema_extra=_unit("1"),
    )
    vertical_m: float = Field(
        50.0,
        ge=5.0,
        le=500.0,
        description="Vertical correlation length of the patches.",
        json_schema_extra=_unit("m"),
    )
    density_ratio: float = Field(
        10.0,
        ge=1.0,
        le=100.0,
        description="Density of the densest part of the patches over the thinnest's.",
        json_schema_extra=_unit("1"),
    )


class BankSpec(_Spec):
    """A fog bank (seahaze.haze_field): dense haze beyond an edge at a distance and bearing
    from the camera, thinner on the camera's side; it drifts with `drift`."""

    distance_m: float = Field(
        ...,
        ge=50.0,
        le=20000.0,
        description="Horizontal distance from the camera to the bank's edge.",
        json_schema_extra=_unit("m"),
    )
    bearing_deg: float = Field(
        0.0,
        ge=-90.0,
        le=90.0,
        description="Direction from the camera into the bank, relative to the camera's "
        "heading (positive to the left, as vessels' bearings); a bank behind the camera would "
        "not be in view.",
        json_schema_extra=_unit("deg"),
    )
    edge_m: float = Field(
        60.0,
        ge=5.0,
        le=2000.0,
        description="Width scale of the bank's edge: the density goes 88 % of the way within "
        "2 edge_m of it.",
        json_schema_extra=_unit("m"),
    )
    near_ratio: float = Field(
        0.15,
        ge=0.01,
        le=1.0,
        description="Density on the camera's side of the edge relative to inside the bank.",
        json_schema_extra=_unit("1"),
    )


class DriftSpec(_Spec):
    """How the patches and the bank move with the wind in a sequence (`m(x − u t)`)."""

    speed_m_s: float = Field(
        0.0,
        ge=0.0,
        le=30.0,
        description="Speed of the haze's drift.",
        json_schema_extra=_unit("m/s"),
    )
    toward_deg: float = Field(
        0.0,
        ge=-180.0,
        le=180.0,
        description="Direction the haze drifts toward, relative to the camera's heading "
        "(positive to the left); the patches are stretched along it.",
        json_schema_extra=_unit("deg"),
    )


class HazeSpec(_Spec):
    """The haze whose extinction is set by the visibility of each level: a homogeneous layer
    up to `top_m`, or with `fog_layer` a fog layer under thinner haze."""

    levels: list[Annotated[float, Field(ge=MIN_LEVEL_M, le=MAX_LEVEL_M)]] = Field(
        default_factory=lambda: [float(v) for v in GRADED_LEVELS_M],
        min_length=1,
        max_length=MAX_LEVELS,
        description="Visibilities to render (`--vis` overrides); default the 11 graded levels. "
        f"At most {MAX_LEVELS}, each within {MIN_LEVEL_M:g}..{MAX_LEVEL_M:g} m and a different "
        "whole number of metres (the level folders `v0300`… carry whole metres).",
        json_schema_extra=_unit("m"),
    )
    threshold: Threshold = Field(
        Threshold.KOSCHMIEDER,
        description="Contrast threshold linking visibility to extinction: `koschmieder` (2 %, "
        "sigma = 3.912/V) or `mor` (5 %, sigma = 2.996/V).",
    )
    extinction_spectrum: ExtinctionSpectrum = Field(
        ExtinctionSpectrum.GREY,
        description="Wavelength dependence of the extinction: `grey` (the same sigma in R, G and "
        "B, as in the MSVD paper) or `kim` (sigma550 · (λ/550 nm)^-q per channel with Kim's "
        "q(V): grey in fog at V ≤ 500 m, up to q = 0.98 at 4000 m; distant objects redden). "
        "The visibility label stays defined at 550 nm; see docs/physics.md.",
    )
    albedo: float = Field(
        0.998,
        ge=0.0,
        le=1.0,
        description="Single-scattering albedo of the haze particles (sea salt and droplets "
        "barely absorb).",
        json_schema_extra=_unit("1"),
    )
    g: float = Field(
        0.75,
        ge=-0.99,
        le=0.99,
        description="Henyey–Greenstein asymmetry parameter of the haze phase function.",
        json_schema_extra=_unit("1"),
    )
    top_m: float = Field(
        300.0,
        gt=0.0,
        le=5000.0,
        description="Height of the top of the haze layer above sea level.",
        json_schema_extra=_unit("m"),
    )
    fog_layer: FogLayerSpec | None = Field(
        None,
        description="A fog layer under thinner haze up to `top_m` (default none: the haze is "
        "homogeneous up to `top_m`). See docs/physics.md, 'A fog layer'.",
    )
    patches: PatchesSpec | None = Field(
        None,
        description="Patches of denser and thinner fog across the sea (default none). With "
        "`patches` or `bank` a level's visibility is that of the mean extinction along the "
        "horizontal lines of sight at camera height over the view (docs/physics.md, 'Haze "
        "that varies across the sea'). `physical` renders each pixel's equivalent profile, lit "
        "by the patches' or the bank's own diffuse field: validated from 300 m for patches "
        "alone and for a bank alone, from 1000 m (within 3.5 %) for both (docs/physics.md, "
        "'Validated range of each mode'); `reference` path-traces the field.",
    )
    bank: BankSpec | None = Field(
        None,
        description="A fog bank beyond an edge (default none); combines with `patches` and "
        "`fog_layer`.",
    )
    drift: DriftSpec = Field(
        default_factory=DriftSpec,
        description="How `patches` and `bank` move in a sequence (default still).",
    )

    @model_serializer(mode="wrap")
    def _omit_uniform_across(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # Haze without patches or a bank keeps a recorded config byte-identical to before
        # they existed.
        data = handler(self)
        for key in ("patches", "bank"):
            if getattr(self, key) is None:
                data.pop(key, None)
        if self.drift == DriftSpec():
            data.pop("drift", None)
        return data

    @model_validator(mode="after")
    def _fog_below_the_top(self) -> HazeSpec:
        fog = self.fog_layer
        if fog is not None and fog.top_m + 2.0 * fog.edge_m > self.top_m:
            raise ValueError(
                f"fog_layer.top_m + 2 fog_layer.edge_m ({fog.top_m + 2.0 * fog.edge_m:g} m) "
                f"must not pass top_m ({self.top_m:g} m): raise top_m or lower the fog"
            )
        return self

    @field_validator("levels")
    @classmethod
    def _distinct_level_names(cls, levels: list[float]) -> list[float]:
        clash = level_name_clash(levels)
        if clash:
            raise ValueError(clash)
        return levels


class LabelsSpec(_Spec):
    """Which vessels get a box."""

    min_box_px: float = Field(
        2.0,
        ge=1.0,
        le=1000.0,
        description="Smallest box width and height that is labelled.",
        json_schema_extra=_unit("px"),
    )
    min_visible_fraction: float = Field(
        0.1,
        ge=0.0,
        le=1.0,
        description="Smallest visible share of a vessel's unoccluded pixels that is labelled.",
        json_schema_extra=_unit("1"),
    )
    write_visible: bool = Field(
        False,
        description="Also write per level the labels of the vessels seen in that level's image "
        "(`labels_visible/<level>/`, `coco_visible/<level>.json`): those whose contrast "
        "against their local background exceeds the threshold of `haze.threshold` (2 % or "
        "5 %). `labels/` keeps every labelled vessel at every level, the MSVD paper's "
        "protocol. See docs/metric.md.",
    )


EXPOSURE_RANGE = (1.0e-3, 1.0e3)
"""Allowed fixed ``render.exposure``; ``auto`` gives about 3–6 under the physical sun and sky."""


class EstimatorSpec(_Spec):
    """The `physical` estimator's tuning (seahaze.render.estimator.EstimatorSettings); every
    field left out (null) keeps seahaze's measured default (docs/benchmarks.md)."""

    bounces: int | None = Field(
        None, ge=1, le=16, description="Surface interactions per camera path (default 3)."
    )
    camera_points: int | None = Field(
        None,
        ge=1,
        le=8,
        description="Stratified in-scattering points on the camera segment (default 2).",
    )
    glint_share: float | None = Field(
        None,
        ge=0.0,
        le=1.0,
        description="Share of a hull's next directions drawn toward the sea's sun glint "
        "(default 0.7; 0: BSDF sampling alone).",
    )
    vessel_light_share: float | None = Field(
        None,
        ge=0.0,
        le=1.0,
        description="Samples per pixel of the vessel-light pass as a share of the main pass's, "
        "rounded up (default 1/14; 0 leaves the pass out).",
    )
    vessel_light_radius_px: int | None = Field(
        None,
        ge=0,
        le=64,
        description="Radius of the box filter smoothing the vessel-light pass within each "
        "segment of the image (default 6 px; 0: unsmoothed).",
    )
    near_share: float | None = Field(
        None,
        ge=0.0,
        le=1.0,
        description="Share of the vessel-light probes' points drawn near a vessel (default 0.5).",
    )
    aim_share: float | None = Field(
        None,
        ge=0.0,
        le=1.0,
        description="Share of the vessel-light probes aimed at a vessel (default 0.5).",
    )
    table_photons: int | None = Field(
        None,
        ge=1024,
        le=1 << 24,
        description="Photons per level of the diffuse tables (default: by the pass's size, "
        "2^17 to 2^20).",
    )
    bank_photons: int | None = Field(
        None,
        ge=1024,
        le=1 << 24,
        description="Photons per level of a fog bank's or patches' own diffuse field "
        "(default: the diffuse tables' number).",
    )


class CameraModelSpec(_Spec):
    """A camera's character on the PNGs (seahaze.camera_model): lens blur and veiling glare,
    sensor shot and read noise, JPEG compression. Applied the same way to the clean image and
    every level; the EXRs stay the linear, noise-free radiance (docs/dataset-format.md)."""

    psf_sigma_px: float = Field(
        0.6,
        ge=0.0,
        le=8.0,
        description="Standard deviation of the lens's Gaussian core (a discrete Gaussian, "
        "whose second moment is exactly this); 0: no core blur. Diffraction alone gives "
        "0.42·λ·N, 0.54 px at f/8 for 550 nm and 3.45 µm pixels (docs/physics.md).",
        json_schema_extra=_unit("px"),
    )
    halo_fraction: float = Field(
        0.0,
        ge=0.0,
        le=0.5,
        description="Share of each pixel's light spread into a wide halo, the veiling glare of "
        "lens and housing (ISO 9358; 0.01–0.05 for camera lenses); 0: none.",
    )
    halo_sigma_px: float = Field(
        30.0,
        ge=1.0,
        le=500.0,
        description="Standard deviation of the veiling-glare halo (a discrete Gaussian).",
        json_schema_extra=_unit("px"),
    )
    full_well_e: float | None = Field(
        10700.0,
        ge=100.0,
        le=1.0e6,
        description="Electrons a pixel collects at the PNG's white (linear 1 after exposure): "
        "the saturation capacity at base gain, less at a higher gain; it sets the shot noise. "
        "Default: Sony IMX250 (3.45 µm pixels). null: no sensor noise.",
        json_schema_extra=_unit("e-"),
    )
    read_noise_e: float = Field(
        1.8,
        ge=0.0,
        le=100.0,
        description="Temporal dark (read) noise, RMS (EMVA 1288; IMX250 about 1.8, IMX174 "
        "6.8). Ignored without `full_well_e`.",
        json_schema_extra=_unit("e-"),
    )
    jpeg_quality: int | None = Field(
        None,
        ge=1,
        le=95,
        description="JPEG quality (Pillow, 4:2:0 chroma): each PNG holds the decoded JPEG of "
        "its pixels, so the dataset stays PNG. null: no compression.",
    )
    shutter_s: float = Field(
        0.0,
        ge=0.0,
        le=0.5,
        description="Exposure time of a global shutter: each frame of a sequence is blurred "
        "by what moves during it, centred on the frame's time (the camera on its platform, "
        "the vessels on their courses; seahaze.motion_blur). 0: an instant. A still is "
        "always an instant (only a sequence moves). 1/60 s = 0.0167.",
        json_schema_extra=_unit("s"),
    )
    white_balance: Literal["illuminant", "off"] = Field(
        "illuminant",
        description="`illuminant`: the camera balances its white to the scene's daylight "
        "(the colour of the sun's and sky's light on a level surface: a white card reads "
        "grey, as a camera's daylight or auto setting makes it), so haze lit by a warm sun "
        "is grey in the PNGs; `off`: the renderer's D65 white (the light's own colour).",
    )

    @model_serializer(mode="wrap")
    def _omit_instant(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # An instant's recorded config and meta stay byte-identical to before the shutter.
        data = handler(self)
        if self.shutter_s == 0.0:
            data.pop("shutter_s", None)
        return data


class RenderSpec(_Spec):
    """How the scene is rendered."""

    mode: Literal["physical", "reference", "asm"] = Field(
        "physical",
        description="Hazy-level renderer: `physical` (seahaze's haze integrator: analytic "
        "transmittance, sun single scattering with shadow rays, tabulated multiple scattering), "
        "`reference` (Mitsuba volpath, slow and noisy) or `asm` (composite of the clean image, "
        "distance and a horizon airlight). See docs/physics.md.",
    )
    spp: int = Field(
        64,
        ge=1,
        le=65536,
        description="Samples per pixel of the clean and `reference` renders (`--spp` overrides).",
    )
    seed: int = Field(
        0,
        ge=0,
        le=2**31 - 1,
        description="Master seed: sampling noise, and the sea and layout when they have no "
        "seed of their own (`--seed` overrides).",
    )
    variant: Literal["auto", "cuda_ad_rgb", "llvm_ad_rgb"] = Field(
        "auto",
        description="Mitsuba variant: `auto` (`cuda_ad_rgb` where a GPU works, else "
        "`llvm_ad_rgb`), `cuda_ad_rgb` or `llvm_ad_rgb` (no other variant can render seahaze's "
        "passes).",
    )
    max_depth: int = Field(
        -1,
        ge=-1,
        le=4096,
        description="Longest light path of Mitsuba `volpath` (the `reference` levels and the "
        "`asm` airlight): -1 unbounded, ended by Russian roulette only (unbiased). A bound "
        "truncates the many scattering events of dense haze: 64 made V = 50 m 2.3x too dark.",
    )
    airlight_spp: int = Field(
        1024,
        ge=16,
        le=1 << 20,
        description="Samples per pixel of the small horizon render that gives the `asm` airlight.",
    )
    exposure: float | Literal["auto"] = Field(
        "auto",
        description="Linear exposure applied before sRGB encoding, within 0.001..1000 (0 or "
        "less is black, 1e300 white); `auto` maps the clean image's horizon sky to 0.6 (about "
        "3–6 under the physical sun and sky).",
    )
    write_exr: bool = Field(True, description="Also write linear radiance as EXR for every image.")
    estimator: EstimatorSpec = Field(
        default_factory=EstimatorSpec,
        description="The `physical` estimator's tuning; leave it out for the measured defaults.",
    )
    denoise: Literal["off", "on"] = Field(
        "off",
        description="`on`: Intel Open Image Denoise (the optional `pyoidn` package, `pip install "
        "seahaze[denoise]`) filters the clean image and every level the same way, guided by "
        "albedo and normal buffers; the PNGs and the contrasts in `meta` are the denoised "
        "images, the EXRs stay the undenoised linear radiance (`--denoise` overrides; "
        'docs/benchmarks.md, "Ground-truth noise").',
    )
    dither: Literal["on", "off"] = Field(
        "on",
        description="`on`: noise of ±1 code (triangular) is added to each 8-bit PNG value "
        "before rounding, so a smooth hazy sky keeps its gradient as an even grain instead of "
        "bands one code apart (seeded from `render.seed`, the scene and the image: the same "
        "config gives the same bytes; clipped black and white stay); `off`: the nearest code. "
        "The EXRs are not touched. See docs/dataset-format.md and docs/benchmarks.md, "
        '"Why are the PNGs dithered?".',
    )
    camera_model: CameraModelSpec | None = Field(
        None,
        description="A camera's blur, noise and compression on every PNG (clean and levels "
        "alike, seeded from `render.seed` and the scene: the same config gives the same "
        "bytes); `{}` for a typical machine-vision camera, null (default) for none. The EXRs "
        'are not touched. See docs/dataset-format.md, "The camera model".',
    )

    @field_validator("denoise", "dither", mode="before")
    @classmethod
    def _on_off_from_bool(cls, value: Any) -> Any:
        # YAML 1.1 (PyYAML) reads a bare on/off as a boolean.
        return {True: "on", False: "off"}.get(value, value) if isinstance(value, bool) else value

    @model_serializer(mode="wrap")
    def _omit_default_dither(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # The default keeps a recorded config byte-identical to before the field existed.
        data = handler(self)
        if self.dither == "on":
            data.pop("dither", None)
        if self.camera_model is None:  # likewise for configs recorded before the camera model
            data.pop("camera_model", None)
        return data

    @field_validator("exposure")
    @classmethod
    def _exposure_in_range(cls, value: float | str) -> float | str:
        low, high = EXPOSURE_RANGE
        if value != "auto" and not low <= float(value) <= high:
            raise ValueError(
                f"exposure must be 'auto' or within {low:g}..{high:g}, got {value:g} "
                "(0 or less gives a black image, a huge value a white one)"
            )
        return value


_AngleEnd = Annotated[float, Field(ge=-360.0, le=360.0)]
_ElevationEnd = Annotated[float, Field(ge=DAYLIGHT_SUN_DEG[0], le=DAYLIGHT_SUN_DEG[1])]
_TwilightEnd = Annotated[float, Field(ge=TWILIGHT_SUN_DEG[0], le=TWILIGHT_SUN_DEG[1])]
_WindEnd = Annotated[float, Field(ge=0.0, le=40.0)]
_HeightEnd = Annotated[float, Field(ge=0.5, le=1000.0)]
_PitchEnd = Annotated[float, Field(ge=-60.0, le=30.0)]
_FovEnd = Annotated[float, Field(gt=1.0, le=120.0)]
_RollEnd = Annotated[float, Field(ge=-45.0, le=45.0)]
_OktaEnd = Annotated[int, Field(ge=1, le=7)]
CAMERA_VARIATION = ("camera_height_m", "camera_pitch_deg", "camera_fov_deg", "camera_roll_deg")
"""Variation ranges of the camera's perspective (issue 17), left out of a recorded config
when unset so configs recorded before them stay byte-identical."""


class VariationSpec(_Spec):
    """Per-scene variation of a batch (`seahaze render --scenes N`).

    Scene `i` of a batch gets its own seed, derived from the master seed (`--seed`, else
    `render.seed`), the scene file's name and `i`; each range given here is sampled uniformly
    with that seed, and a range left out keeps the scene's value. Without `--scenes` this
    section is ignored.
    """

    camera_heading_deg: tuple[_AngleEnd, _AngleEnd] | None = Field(
        None,
        description="Range `[low, high]` of `camera.heading_deg` (each end within -360..360).",
        json_schema_extra=_unit("deg"),
    )
    sun_elevation_deg: tuple[_ElevationEnd, _ElevationEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sun.elevation_deg` (each end within 0.5..89.5).",
        json_schema_extra=_unit("deg"),
    )
    sun_azimuth_deg: tuple[_AngleEnd, _AngleEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sun.azimuth_deg` (each end within -360..360).",
        json_schema_extra=_unit("deg"),
    )
    wind_speed: tuple[_WindEnd, _WindEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sea.wind_speed` (each end within 0..40); it "
        "replaces `sea.beaufort`.",
        json_schema_extra=_unit("m/s"),
    )
    sea_direction_deg: tuple[_AngleEnd, _AngleEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sea.direction_deg` (each end within -360..360).",
        json_schema_extra=_unit("deg"),
    )
    camera_height_m: tuple[_HeightEnd, _HeightEnd] | None = Field(
        None,
        description="Range `[low, high]` of `camera.height_m` (each end within 0.5..1000; "
        "5..60 for a sequence's shore mast).",
        json_schema_extra=_unit("m"),
    )
    camera_pitch_deg: tuple[_PitchEnd, _PitchEnd] | None = Field(
        None,
        description="Range `[low, high]` of `camera.pitch_deg` (each end within -60..30).",
        json_schema_extra=_unit("deg"),
    )
    camera_fov_deg: tuple[_FovEnd, _FovEnd] | None = Field(
        None,
        description="Range `[low, high]` of `camera.fov_deg` (each end within 1..120, 1 excluded).",
        json_schema_extra=_unit("deg"),
    )
    camera_roll_deg: tuple[_RollEnd, _RollEnd] | None = Field(
        None,
        description="Range `[low, high]` of `camera.roll_deg` (each end within -45..45).",
        json_schema_extra=_unit("deg"),
    )
    sky_models: list[Literal["clear", "broken", "overcast", "twilight"]] | None = Field(
        None,
        min_length=1,
        description="`sky.model`s to draw from, each equally likely (a name twice counts "
        "twice), e.g. `[clear, broken, overcast, overcast]` for mostly grey days; a scene "
        "drawn `twilight` draws its sun from `twilight_sun_elevation_deg`.",
    )
    twilight_sun_elevation_deg: tuple[_TwilightEnd, _TwilightEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sun.elevation_deg` for a scene whose sky is "
        "`twilight` (each end within -6..0; default: all of civil twilight, -6..0, where "
        "`sky_models` draws it, the template's sun where the template is twilight).",
        json_schema_extra=_unit("deg"),
    )
    cloud_oktas: tuple[_OktaEnd, _OktaEnd] | None = Field(
        None,
        description="Range `[low, high]` of `sky.clouds.oktas`, whole oktas drawn uniformly "
        "(each end within 1..7); only where the sky may be `broken`.",
        json_schema_extra=_unit("okta"),
    )
    resample_clouds: bool = Field(
        True,
        description="Give every scene of a broken sky its own cloud layer (a "
        "`sky.clouds.seed` is replaced by one derived from the scene's seed).",
    )
    resample_sea: bool = Field(
        True,
        description="Give every scene new wave phases (a `sea.seed` is replaced by one derived "
        "from the scene's seed).",
    )
    resample_layout: bool = Field(
        True,
        description="Give every scene a new `vessels.sample` layout (its `seed` is replaced by "
        "one derived from the scene's seed); `vessels.placed` stay where they are.",
    )

    @model_serializer(mode="wrap")
    def _omit_unset_camera(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        data = handler(self)
        for key in CAMERA_VARIATION:
            if getattr(self, key) is None:
                data.pop(key, None)
        # The clouds' settings too, at their defaults: configs recorded before them read alike.
        for key in ("sky_models", "cloud_oktas", "twilight_sun_elevation_deg"):
            if getattr(self, key) is None:
                data.pop(key, None)
        if self.resample_clouds:
            data.pop("resample_clouds", None)
        return data

    @model_validator(mode="after")
    def _ordered_ranges(self) -> VariationSpec:
        for name in type(self).model_fields:
            value = getattr(self, name)
            if isinstance(value, tuple) and value[0] > value[1]:
                raise ValueError(
                    f"{name} must be [low, high] with low <= high, got [{value[0]:g}, {value[1]:g}]"
                )
        return self


SHORE_MAST_M = (5.0, 60.0)
"""Heights of a shore platform's fixed mast (m): a harbour pole to a coastal VTS tower."""


class SequenceSpec(_Spec):
    """A scene rendered as a sequence of frames: vessels move, the sea evolves.

    Frame ``i`` shows time ``sea.time_s + i / fps``; every vessel's pose in the YAML (or drawn
    by the sampler) is its pose at mid-sequence, so the vessels stay near where the scene puts
    them. See docs/dataset-format.md ("Sequences").
    """

    frames: int = Field(
        100,
        ge=1,
        le=10000,
        description="Number of frames, required in a scene file (a `sequence:` without it is "
        "refused: each frame is a full render, so no count is assumed); `--frames` overrides "
        "it. Each frame is a scene of the batch, which holds at most 10,000.",
    )
    fps: float = Field(
        10.0,
        gt=0.0,
        le=120.0,
        description="Frame rate (`--fps` overrides).",
        json_schema_extra=_unit("1/s"),
    )
    platform: Literal["shore", "ship"] = Field(
        "shore",
        description="Camera platform: `shore`, a fixed mast; `ship`, a mast on an own ship "
        "sailing at `own_speed_kn` and heaving, pitching and rolling with the sea (see "
        "`camera_mount`). Either way `camera.height_m` (5..60 m) is the camera's height above "
        "the (own ship's) waterline.",
    )
    camera_mount: Literal["level", "rigid"] = Field(
        "level",
        description="How the camera sits on the own ship's mast (`ship` only). `level`: "
        "roll-stabilised, the image keeps `camera.roll_deg` and the view's pitch follows the "
        "ship's pitch and roll projected on the view direction. `rigid`: fixed to the hull, "
        "the camera turns with the ship's whole attitude (its pitch and roll from the sea "
        "under the hull), so the horizon tilts and sways with the ship's roll.",
    )
    own_speed_kn: float = Field(
        0.0,
        ge=0.0,
        le=40.0,
        description="Own ship's speed through the water (`ship` only); at mid-sequence the own "
        "ship is where the scene's camera is.",
        json_schema_extra=_unit("kn"),
    )
    own_heading_deg: float | None = Field(
        None,
        ge=-360.0,
        le=360.0,
        description="Own ship's course, counter-clockwise from +x (`ship` only); default "
        "`camera.heading_deg` (the camera looks ahead).",
        json_schema_extra=_unit("deg"),
    )
    own_length_m: float = Field(
        60.0,
        ge=5.0,
        le=400.0,
        description="Own ship's length (`ship` only): its hull averages the waves it heaves "
        "and pitches on (beam a sixth of it), and no vessel may come within its footprint.",
        json_schema_extra=_unit("m"),
    )

    @model_validator(mode="after")
    def _ship_settings(self) -> SequenceSpec:
        if self.platform == "shore" and (self.own_speed_kn or self.own_heading_deg is not None):
            raise ValueError(
                "own_speed_kn and own_heading_deg describe an own ship; allowed: platform ship, "
                "or leave them out for a shore mast"
            )
        if self.platform == "shore" and self.camera_mount != "level":
            raise ValueError(
                f"camera_mount {self.camera_mount} mounts the camera on an own ship; allowed: "
                "platform ship, or camera_mount level for a shore mast"
            )
        return self

    @model_serializer(mode="wrap")
    def _omit_defaults_added_later(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A level mount and one encounter keep a recorded config byte-identical to before
        # these fields existed.
        data = handler(self)
        if self.camera_mount == "level":
            data.pop("camera_mount", None)
        if self.encounters == 1:
            data.pop("encounters", None)
        return data

    encounter: Literal["none", "crossing", "head_on", "overtaking", "random"] = Field(
        "none",
        description="Encounter set up between the first two vessels that can move (a stopped "
        "one gets a speed drawn in its class's range): the second is moved to pass the first "
        "at mid-sequence, crossing (60..120 deg apart), head-on or overtaking (which sets the "
        "speeds: the faster class at its top speed, the other at 0.6 of that or its class's "
        "lowest); `random` draws one of the three from the seed.",
    )
    encounters: int = Field(
        1,
        ge=1,
        le=8,
        description="How many encounters `encounter` sets up: between the 1st and 2nd vessels "
        "that can move, then the 3rd and 4th, and so on (`random` draws each pair's kind).",
    )

    @model_validator(mode="after")
    def _encounter_pairs(self) -> SequenceSpec:
        if self.encounters > 1 and self.encounter == "none":
            raise ValueError(
                f"encounters {self.encounters} needs an encounter kind; allowed: encounter "
                "crossing, head_on, overtaking or random, or leave encounters out"
            )
        return self

    @property
    def duration_s(self) -> float:
        """Time from the first frame to the last (s)."""
        return (self.frames - 1) / self.fps

    def time_s(self, frame: int) -> float:
        """Time of ``frame`` after the first frame (s)."""
        return frame / self.fps


_SEQUENCE_NEEDS = (
    "a sequence needs its number of frames, e.g. sequence: {frames: 50, fps: 10} (frames "
    "1..10000; fps 0 (excluded)..120, default 10), or leave sequence: out for a still image; "
    f"allowed fields: {', '.join(SequenceSpec.model_fields)}"
)
"""What an empty or frame-less ``sequence:`` is told."""


class SceneSpec(_Spec):
    """A whole scene: camera, sun, sky, sea, vessels, haze and render settings."""

    name: str | None = Field(
        None,
        pattern=r"^[A-Za-z0-9_.-]{1,64}$",
        description="Scene name used for file names; default the YAML file's stem.",
    )
    camera: CameraSpec = Field(default_factory=CameraSpec)
    sun: SunSpec = Field(default_factory=SunSpec)
    sky: SkySpec = Field(default_factory=SkySpec)
    sea: SeaSpec = Field(default_factory=SeaSpec)
    vessels: VesselsSpec = Field(default_factory=VesselsSpec)
    haze: HazeSpec = Field(default_factory=HazeSpec)
    labels: LabelsSpec = Field(default_factory=LabelsSpec)
    render: RenderSpec = Field(default_factory=RenderSpec)
    variation: VariationSpec = Field(
        default_factory=VariationSpec,
        description="Ranges the scenes of a batch (`--scenes N`) are drawn from.",
    )
    sequence: SequenceSpec | None = Field(
        None, description="Render the scene as a sequence of frames; default one still frame."
    )

    @field_validator("sequence", mode="before")
    @classmethod
    def _sequence_not_empty(cls, value: Any) -> Any:
        # A field validator sees None only when the file says `sequence:` with nothing under
        # it (a left-out section is not validated): that rendered a still image, though the
        # file asks for a sequence.
        if value is None:
            raise ValueError(f"an empty sequence block; {_SEQUENCE_NEEDS}")
        return value

    @field_validator("sequence")
    @classmethod
    def _sequence_has_frames(cls, value: SequenceSpec | None) -> SequenceSpec | None:
        # `sequence: {}` once rendered 100 frames (minutes to hours) without a word: the frame
        # count of a file's sequence is never assumed. Checked after SequenceSpec's own rules,
        # so a field it refuses is reported first.
        if value is not None and "frames" not in value.model_fields_set:
            raise ValueError(f"frames is missing; {_SEQUENCE_NEEDS}")
        return value

    @model_serializer(mode="wrap")
    def _omit_still(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # A still scene's recorded config stays byte-identical to before sequences existed.
        data = handler(self)
        if self.sequence is None:
            data.pop("sequence", None)
        return data

    @model_validator(mode="after")
    def _shore_mast(self) -> SceneSpec:
        low, high = SHORE_MAST_M
        if self.sequence is not None and not low <= self.camera.height_m <= high:
            raise ValueError(
                f"camera.height_m {self.camera.height_m:g} m does not fit a sequence's "
                f"{self.sequence.platform} mast; allowed: {low:g}..{high:g} m"
            )
        varied = self.variation.camera_height_m
        if self.sequence is not None and varied and not low <= varied[0] <= varied[1] <= high:
            raise ValueError(
                f"variation.camera_height_m [{varied[0]:g}, {varied[1]:g}] does not fit a "
                f"sequence's mast; allowed: within {low:g}..{high:g} m"
            )
        return self

    def may_be_broken(self) -> bool:
        """Whether this scene, or a scene of a batch drawn from it, has a broken sky."""
        drawn = self.variation.sky_models
        return self.sky.model == "broken" or (drawn is not None and "broken" in drawn)

    @model_validator(mode="after")
    def _sun_fits_the_sky(self) -> SceneSpec:
        # Hosek–Wilkie holds for a sun above the horizon only; the twilight model for one
        # below it.
        elevation, model = self.sun.elevation_deg, self.sky.model
        low, high = TWILIGHT_SUN_DEG if model == "twilight" else DAYLIGHT_SUN_DEG
        if not low <= elevation <= high:
            other = "clear, broken or overcast" if model == "twilight" else "twilight"
            raise ValueError(
                f"sun.elevation_deg {elevation:g}: a '{model}' sky takes {low:g}..{high:g} deg; "
                f"for this sun set sky.model to {other}"
            )
        # A batch's scenes (the same rules hold for the template and every scene drawn from
        # it, which keeps its variation): a daylight sky takes a daylight sun, the template's
        # or drawn; a twilight one draws its own (or keeps a twilight template's). A batch of
        # both draws each its own, so the daylight one is drawn too.
        variation, drawn = self.variation, self.variation.sky_models
        daylight = [m for m in drawn or [model] if m != "twilight"]
        twilight = "twilight" in (drawn or [model])
        if daylight and variation.sun_elevation_deg is None and (twilight or model == "twilight"):
            raise ValueError(
                f"variation.sky_models: its {daylight[0]} skies need a sun above the horizon "
                f"({DAYLIGHT_SUN_DEG[0]:g}..{DAYLIGHT_SUN_DEG[1]:g} deg), which a twilight "
                "sun is not: give variation.sun_elevation_deg to draw theirs"
            )
        if variation.sun_elevation_deg is not None and not daylight:
            raise ValueError(
                "variation.sun_elevation_deg draws daylight suns, but every scene's sky is "
                "twilight; use variation.twilight_sun_elevation_deg"
            )
        if variation.twilight_sun_elevation_deg is not None and not twilight:
            raise ValueError(
                "variation.twilight_sun_elevation_deg: no scene of this batch has a twilight "
                "sky; set sky.model: twilight, put twilight in variation.sky_models or remove it"
            )
        return self

    @model_validator(mode="after")
    def _cloud_variation_needs_clouds(self) -> SceneSpec:
        if self.variation.cloud_oktas is not None and not self.may_be_broken():
            raise ValueError(
                f"variation.cloud_oktas: only a `broken` sky has clouds to vary (sky.model is "
                f"'{self.sky.model}'); set sky.model: broken, put broken in "
                "variation.sky_models or remove variation.cloud_oktas"
            )
        return self

    @model_validator(mode="after")
    def _clouds_above_the_haze(self) -> SceneSpec:
        # The sky is drawn beyond the haze layer: a cloud base inside it would be cloud seen
        # through haze that should be around it.
        if self.may_be_broken():
            base = self.sky.cloud_layer.base_height_m
            if base <= self.haze.top_m:
                raise ValueError(
                    f"sky.clouds.base_height_m ({base:g} m) must be above haze.top_m "
                    f"({self.haze.top_m:g} m): raise the cloud base or lower the haze top"
                )
        return self

    @model_validator(mode="after")
    def _sequence_within_the_sea_clock(self) -> SceneSpec:
        # The last frame's sea time must stay within sea.time_s's own limit (a tiny fps once
        # sent the sea to t = 1e300 s without a word).
        if self.sequence is not None:
            last = self.sea.time_s + self.sequence.duration_s
            if not last <= SEA_TIME_LIMIT_S:
                raise ValueError(
                    f"sequence: {self.sequence.frames} frames at {self.sequence.fps:g} fps end at "
                    f"sea time {last:.3g} s, past the sea's limit of {SEA_TIME_LIMIT_S:g} s; "
                    "raise fps, or lower frames or sea.time_s"
                )
        return self


class OverrideError(ValueError):
    """A command-line override that the schema rejects; the message is one line for the user."""


RENDER_MODES: tuple[str, ...] = get_args(RenderSpec.model_fields["mode"].annotation)
"""The hazy-level renderers, in the order the CLI lists them."""
MITSUBA_VARIANTS: tuple[str, ...] = get_args(RenderSpec.model_fields["variant"].annotation)[1:]
"""The Mitsuba variants seahaze renders with, in the order ``auto`` tries them
(:mod:`seahaze.render.variant`)."""


def with_changes(spec: SceneSpec, changes: Mapping[str, Any]) -> SceneSpec:
    """A copy of ``spec`` with nested ``changes`` (a mapping merged into its sections, any other
    value replacing the field) validated by the same schema.

    Raises :class:`OverrideError` with a one-line message naming the first rejected field.
    """
    data = _merged(spec.model_dump(mode="json", by_alias=True), changes)
    try:
        return SceneSpec.model_validate(data)
    except ValueError as err:
        first = err.errors()[0] if hasattr(err, "errors") else None
        where = ".".join(str(p) for p in first["loc"]) if first else ""
        message = str(first["msg"] if first else err).removeprefix("Value error, ")
        raise OverrideError(f"{where}: {message}" if where else message) from None


def _merged(data: dict[str, Any], changes: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(data)
    for key, value in changes.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), dict):
            out[key] = _merged(out[key], value)
        else:
            out[key] = value
    return out


def with_overrides(
    spec: SceneSpec,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    mode: str | None = None,
    variant: str | None = None,
    levels: list[float] | None = None,
    frames: int | None = None,
    fps: float | None = None,
    denoise: str | None = None,
    dither: str | None = None,
) -> SceneSpec:
    """A copy of ``spec`` with the command line's overrides (None: keep the scene's value).

    ``frames`` makes a still scene a sequence (at ``fps``, default 10); ``fps`` alone changes a
    sequence's frame rate and is refused for a still scene, which has no frames to time (it
    once made it a 100-frame sequence).
    """
    if fps is not None and frames is None and spec.sequence is None:
        raise OverrideError(
            f"--fps {fps:g} needs a sequence: pass --frames N too, or add sequence: "
            "{frames: N} to the scene (a still scene has one frame and no frame rate)"
        )
    render = {
        "spp": spp,
        "seed": seed,
        "mode": mode,
        "variant": variant,
        "denoise": denoise,
        "dither": dither,
    }
    changes: dict[str, Any] = {"render": {k: v for k, v in render.items() if v is not None}}
    sequence = {"frames": frames, "fps": fps}
    if any(v is not None for v in sequence.values()):
        changes["sequence"] = {
            **(spec.sequence.model_dump(mode="json") if spec.sequence else {}),
            **{k: v for k, v in sequence.items() if v is not None},
        }
    if resolution is not None:
        changes["camera"] = {"resolution": list(resolution)}
    if levels is not None:
        changes["haze"] = {"levels": list(levels)}
    return with_changes(spec, changes)
