"""The outputs of ``seahaze verify``: the text table, ``report.json``, the contrast plot and the
strips of the rendered calibration views."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import fileio, imaging
from .field import DENSE_RATIO, THIN_RATIO, coverage_note
from .run import LevelMeasurement, LevelReport, VerifyReport, finite_json
from .targets import SKY_MIN_OPTICAL_DEPTH, sky_pixels


def format_report(report: VerifyReport) -> str:
    """The report as a plain-text table: per level the targets, then a summary."""
    cfg = report.config
    lines = [
        f"seahaze verify: mode {cfg['mode']}, {cfg['resolution'][0]}x{cfg['resolution'][1]}, "
        f"{cfg['batches']} batches x {cfg['spp_per_batch']} spp, {cfg['variant']}, "
        f"threshold {cfg['threshold']} ({cfg['contrast_threshold']:g})"
    ]
    for level in report.levels:
        lines += [
            "",
            f"{level.name}: V = {level.visibility_m:g} m, sigma = {level.sigma_per_m:.4e} /m",
            f"  {'target':>6} {'d (m)':>8} {'d/V':>5} {'ℓ/d':>5} {'px':>4} {'C measured':>19} "
            f"{'C expected':>10} {'z':>6} {'tau meas':>8} {'tau exp':>7} {'ratio':>6}",
        ]
        for t in level.targets:
            lines.append(
                f"  {t.index:>6} {t.distance_m:>8.1f} {t.fraction_of_v:>5.2f} "
                f"{t.mean_density:>5.2f} {t.pixels:>4} {t.contrast:>9.4f} ± {t.stderr:<7.4f} "
                f"{t.expected:>10.4f} {t.z:>6.1f} {t.tau_measured:>8.4f} {t.tau_expected:>7.4f} "
                f"{t.tau_ratio:>6.3f}"
            )
        lines.append(
            f"  V measured {level.measured_m:.1f} m ± {level.stderr_fit_m:.1f} (fit) "
            f"± {level.stderr_jackknife_m:.1f} (jackknife); error {level.error:+.2%}, "
            f"chi2/dof {level.chi2_per_dof:.2f}, {level.informative_targets} targets > 3 se"
        )
        lines += _coverage_lines(level)
    lines += [
        "",
        f"{'level':<7} {'V label':>8} {'V measured':>11} {'± se':>7} {'error':>8} "
        f"{'± se':>7} {'tol':>6}  result",
    ]
    for level in report.levels:
        rel_se = level.stderr_m / level.visibility_m
        lines.append(
            f"{level.name:<7} {level.visibility_m:>8g} {level.measured_m:>11.1f} "
            f"{level.stderr_m:>7.1f} {level.error:>+8.2%} {rel_se:>7.2%} "
            f"{level.tolerance:>6.1%}  {'PASS' if level.passed else 'FAIL'}"
        )
        if level.sky_optical_depth < SKY_MIN_OPTICAL_DEPTH:
            lines.append(
                f"  note: the sky beside the targets is only {level.sky_optical_depth:.1f} optical "
                "depths deep in the haze layer: clear sky shows through its top, so Koschmieder's "
                "horizon (the haze's own airlight) is not there to measure against"
            )
        if math.isfinite(rel_se) and 3.0 * rel_se > level.tolerance:
            lines.append(
                f"  note: 3 standard errors ({3 * rel_se:.1%}) exceed the tolerance: the noise "
                "decides this result; raise --spp"
            )
    lines.append(
        f"{'PASS' if report.passed else 'FAIL'}: {sum(lv.passed for lv in report.levels)}/"
        f"{len(report.levels)} levels within tolerance, {report.seconds:.1f} s"
    )
    return "\n".join(lines)


def _coverage_lines(level: LevelReport) -> list[str]:
    """Where the haze varies across the sea: how many targets stand in dense and thin haze,
    and a note when they all stand on one side."""
    if not level.varies_across:
        return []
    lines = [
        f"  across the sea: {level.dense_targets} of {len(level.targets)} targets in dense haze "
        f"(ℓ/d > {DENSE_RATIO:g}), {level.thin_targets} in thin (ℓ/d < {THIN_RATIO:g})"
    ]
    note = coverage_note(level.dense_targets, level.thin_targets, len(level.targets))
    return lines + ([f"  note: {note}"] if note else [])


def write_outputs(
    report: VerifyReport, out: Path, measurements: dict[str, LevelMeasurement] | None = None
) -> list[Path]:
    """Write ``report.json``, ``contrast.png`` (plot) and, given the measurements,
    ``strips.png`` (the rendered calibration views) into ``out``; returns the paths."""
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "report.json", out / "contrast.png"]
    data = {
        "config": report.config,
        "passed": report.passed,
        "seconds": report.seconds,
        "levels": [level.to_json() for level in report.levels],
    }
    fileio.write_json(written[0], finite_json(data))
    plot_contrasts(report, written[1])
    if measurements:
        written.append(out / "strips.png")
        write_strips(measurements, written[2])
    return written


def plot_contrasts(report: VerifyReport, path: Path) -> None:
    """Measured ``|C|`` against each target's reduced length ``ℓ`` (its distance in uniform
    haze) per level, with Koschmieder's ``exp(−σℓ)`` and the fitted curve."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(report.levels)
    cols = min(n, 3)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.0 * cols, 3.8 * rows), squeeze=False, layout="constrained"
    )
    eps = report.config["contrast_threshold"]
    for ax, level in zip(axes.flat, report.levels, strict=False):
        d = np.array([t.reduced_m for t in level.targets])
        c = -np.array([t.contrast for t in level.targets])
        se = np.array([t.stderr for t in level.targets])
        x = np.linspace(0.0, max(1.6 * level.visibility_m, 1.05 * float(np.max(d))), 200)
        ax.plot(x, np.exp(-level.sigma_per_m * x), "k-", lw=1, label="exp(-σℓ), label V")
        if math.isfinite(level.measured_m):
            sigma_fit = -math.log(eps) / level.measured_m
            ax.plot(x, np.exp(-sigma_fit * x), "C1--", lw=1, label="fit")
        ok = c > se
        ax.errorbar(d[ok], c[ok], yerr=se[ok], fmt="o", ms=4, color="C0", label="measured |C|")
        if np.any(~ok):
            ax.plot(
                d[~ok],
                np.maximum(c[~ok], 0) + 2 * se[~ok],
                "v",
                color="C0",
                alpha=0.5,
                label="< noise (2 se)",
            )
        ax.axhline(eps, color="0.6", lw=0.8, ls=":")
        ax.axvline(level.visibility_m, color="0.6", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_ylim(max(1e-4, 0.2 * eps * math.exp(-0.5 * 3.9)), 1.5)
        ax.set_xlabel("reduced length ℓ = ∫ρ ds (m; the distance in uniform haze)")
        ax.set_ylabel("|C|")
        verdict = "PASS" if level.passed else "FAIL"
        ax.set_title(
            f"{level.name}: V {level.measured_m:.0f} ± {level.stderr_m:.0f} m "
            f"({level.error:+.1%}) {verdict}",
            fontsize=10,
        )
        ax.legend(fontsize=7, loc="lower left")
        ax.grid(alpha=0.3, which="both")
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    cfg = report.config
    fig.suptitle(
        f"seahaze verify ({cfg['mode']}, {cfg['spp']} spp, {cfg['resolution'][0]}x"
        f"{cfg['resolution'][1]})",
        fontsize=11,
    )
    with fileio.atomic_target(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def write_strips(measurements: dict[str, LevelMeasurement], path: Path, scale: int = 3) -> None:
    """The mean rendered view of every level, stacked top to bottom, exposed so that the sky
    beside the targets maps to :data:`seahaze.imaging.AUTO_KEY`."""
    images = []
    for m in measurements.values():
        rows, cols = sky_pixels(m.targets[len(m.targets) // 2])
        sky = float(np.mean(imaging.luminance(m.radiance[rows][:, cols])))
        exposure = imaging.AUTO_KEY / sky if sky > 0 else 1.0
        image = imaging.to_srgb8(m.radiance, exposure)
        image = np.repeat(np.repeat(image, scale, axis=0), scale, axis=1)
        images += [image, np.full((4, image.shape[1], 3), 255, np.uint8)]
    fileio.write_png(path, np.concatenate(images[:-1], axis=0))
