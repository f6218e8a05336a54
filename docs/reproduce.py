"""Regenerate docs/reproduction.md: the paper's reported results beside this project's.

Run from anywhere: ``python docs/reproduce.py`` (about 10 s with warm Numba caches).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import scipy.signal

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from model.params import Scenario, Tunnel  # noqa: E402
from model.pipeline import StageCache, run  # noqa: E402
from model.soil.moving_load_2p5d import receptance_2p5d  # noqa: E402
from model.soil.point_load import point_load_response  # noqa: E402

OUT = ROOT / "docs" / "reproduction.md"
MM = 1e3


def pulse_width(t_s: np.ndarray, signal: np.ndarray, level: float) -> float:
    """Duration (s) over which a single pulse stays above ``level`` times its peak."""
    above = t_s[signal >= level * signal.max()]
    return float(above[-1] - above[0])


def band_fraction(f_hz: np.ndarray, psd: np.ndarray, f_max: float) -> float:
    """Share of the PSD's variance between 0 and f_max."""
    return float(np.sum(psd[f_hz <= f_max]) / np.sum(psd))


def spectral_peaks(f_hz: np.ndarray, psd: np.ndarray, f_max: float, count: int) -> list[float]:
    """Frequencies of the ``count`` most prominent local maxima of a PSD below f_max (Hz)."""
    keep = (f_hz > 0.5) & (f_hz <= f_max)
    log_psd = np.log10(psd[keep])
    peaks, props = scipy.signal.find_peaks(log_psd, prominence=0.1)
    order = np.argsort(props["prominences"])[::-1][:count]
    return sorted(float(f) for f in f_hz[keep][peaks[order]])


def peak_match_text(peaks: list[float]) -> str:
    """Which of the paper's Fig. 10 peaks (2, 3, 4 Hz and the 10–12 Hz band) we find (±0.3 Hz)."""
    found = [f"{f:g} Hz" for f in (2.0, 3.0, 4.0) if any(abs(p - f) <= 0.3 for p in peaks)]
    missed = [f"{f:g} Hz" for f in (2.0, 3.0, 4.0) if f"{f:g} Hz" not in found]
    if any(9.7 <= p <= 12.3 for p in peaks):
        found.append("the 10–12 Hz band")
    else:
        missed.append("the 10–12 Hz band")
    text = f"Found: {', '.join(found) or 'none'}."
    return text + (f" Not among our most prominent peaks: {', '.join(missed)}." if missed else "")


def row(*cells) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def beam_on_soil_length(tunnel, soil) -> tuple[float, float, float]:
    """(L, EI, k): the lining as a beam on the soil, L = (4EI/k)^¼ (m).

    EI = E π a³ h (1 + h²/4a²) is the thick tube's bending stiffness; k (N/m²) is the soil's
    own spring per unit length at the wavenumber ξ = 1/L of the bending it resists: the
    inverse of the n = 1 quasi-static displacement of the bare cavity (lining made to vanish)
    under a unit line load, from the 2.5D model at 0.01 Hz. Iterated to a fixed point.
    """
    a, h = tunnel.ring_radius, tunnel.thickness
    bending = tunnel.youngs_modulus * np.pi * a**3 * h * (1 + h**2 / (4 * a**2))
    cavity = Tunnel(youngs_modulus=1.0, density=1e-6)
    length = 25.0
    for _ in range(30):
        xi = 1.0 / length
        u1 = (
            receptance_2p5d(0.01, xi, 0.0, cavity, soil, 1)
            - receptance_2p5d(0.01, xi, 0.0, cavity, soil, 0)
        )[0, 0].real
        spring = 1.0 / u1
        length = (4 * bending / spring) ** 0.25
    return length, bending, spring


def half_width(x_m: np.ndarray, profile: np.ndarray) -> float:
    """Distance from x = 0 at which a profile peaked at x = 0 falls to half its peak (m)."""
    below = np.flatnonzero(profile < 0.5 * profile[0])
    return float(np.interp(0.5 * profile[0], profile[below[0] : below[0] - 2 : -1],
                           x_m[below[0] : below[0] - 2 : -1]))  # fmt: skip


def main() -> None:
    bogie = run(Scenario.preset("single_bogie"), cache=None)
    shared = StageCache()  # the 2.5D run reuses the paper run's vehicle–track stage
    train = run(Scenario.paper(), cache=shared)
    moving = run(Scenario.paper_2p5d(), cache=shared)
    smooth_scenario = Scenario.paper_2p5d()
    smooth_scenario.irregularity.enabled = False
    smooth = run(smooth_scenario, cache=shared)
    readings = {
        name: run(Scenario.preset(name), cache=None)
        for name in ("paper_soil_wave_speeds", "paper_soil_lame")
    }

    vt = bogie.vehicle_track
    model_peak, boef_peak = vt.block_disp_m.max(), vt.winkler_block_disp_m.max()
    model_width = pulse_width(vt.t_s, vt.block_disp_m, 0.1)
    boef_width = pulse_width(vt.t_s, vt.winkler_block_disp_m, 0.1)
    # at t = 0 the leading wheel is numerics.approach_distance (10 m) before the block
    model_far, boef_far = vt.block_disp_m[0], vt.winkler_block_disp_m[0]
    bogie_fraction = band_fraction(bogie.load.f_hz, bogie.load.psd, 30.0)
    train_fraction = band_fraction(train.load.f_hz, train.load.psd, 30.0)
    peaks = spectral_peaks(train.soil.f_hz, train.soil.interface_psd, 20.0, 6)
    s = train.summary()
    track = Scenario.paper().track
    winkler_share = (
        track.winkler_beta * track.block_spacing / 2 * Scenario.paper().vehicle.static_wheel_load
    )
    depth, peak = train.soil.depth_m, train.soil.peak_disp_m
    at = {d: float(np.interp(d, depth, peak)) * MM for d in (0.0, 11.0, 35.0)}

    lines = [
        "# Reproduction of the paper's results",
        "",
        "Generated by `python docs/reproduce.py` from the presets in `model/data/presets.json`;",
        "do not "
        "edit by hand. Scenario: `Scenario.paper()` (six-car Type A train, 80 km/h, FRA class 6,",
        "seed 2024, soil E = 6 MPa, ν = 0.3) and the preset `single_bogie` (the paper's Fig. 1",
        "model) for the figures the paper computed with one bogie. Paper numbers are read from its",
        "text; its figures carry no other values we could read off reliably.",
        "",
        "## Vehicle–track stage (paper §4.1)",
        "",
        row("quantity", "this project", "paper", "ratio", "why they differ"),
        row("---", "---", "---", "---", "---"),
        row(
            "Fig. 5: peak block (sleeper) displacement, single bogie",
            f"{model_peak * MM:.3f} mm",
            "not stated",
            "–",
            f"The Winkler (BOEF) curve of the same track gives {boef_peak * MM:.3f} mm "
            f"(ratio {model_peak / boef_peak:.2f}); the paper's Table 2 track values are "
            "missing, ours are docs/model.md's assumptions.",
        ),
        row(
            "Fig. 5: duration above 10 % of the peak, model vs BOEF",
            f"{model_width * 1e3:.1f} ms vs {boef_width * 1e3:.1f} ms",
            "model decays slower",
            f"{model_width / boef_width:.3f}",
            f"Same sense as the paper, but small here: 10 m from the wheel the model's block "
            f"is still {model_far * 1e6:.2f} µm down, the BOEF's {boef_far * 1e6:.3f} µm. With "
            "docs/model.md's stiff supports the two nearly coincide; the paper's larger gap may "
            "come from its unknown track values or mode count.",
        ),
        row(
            "Fig. 6: peak force into the invert under one block, full train",
            f"{s['peak_invert_force_N'] / 1e3:.1f} kN",
            "not stated",
            "–",
            f"The Winkler share βL_s/2 of one 61.1 kN wheel is {winkler_share / 1e3:.1f} kN; "
            "the paper gives no number. Line load q = 2F_b/L_s peaks at "
            f"{s['peak_line_load_N_per_m'] / 1e3:.1f} kN/m.",
        ),
        row(
            "Fig. 7: share of load variance below 30 Hz, single bogie",
            f"{bogie_fraction:.2%} ({1 - bogie_fraction:.1e} above)",
            "main content 0–30 Hz",
            "–",
            f"Agrees. Full train: {1 - train_fraction:.1e} above 30 Hz. Pads and "
            "fasteners filter the "
            "high-frequency wheel–rail force, as the paper says.",
        ),
        "",
        "## Tunnel–soil stage (paper §4.2)",
        "",
        row("quantity", "this project", "paper", "ratio", "why they differ"),
        row("---", "---", "---", "---", "---"),
        row(
            "Fig. 10: interface-displacement PSD peaks below 20 Hz",
            ", ".join(f"{f:.2f}" for f in peaks) + " Hz",
            "≈ 2, 3, 4 and 10–12 Hz",
            "–",
            peak_match_text(peaks) + " See the note below.",
        ),
        row(
            "Fig. 11: peak displacement at the invert",
            f"{at[0.0]:.2f} mm",
            "6.72 mm",
            f"{at[0.0] / 6.72:.2f}",
            "See the note below.",
        ),
        row(
            "Fig. 11: peak displacement at 11 m",
            f"{at[11.0]:.2f} mm",
            "2.94 mm",
            f"{at[11.0] / 2.94:.2f}",
            "See the note below.",
        ),
        row(
            "Conclusions: peak displacement at the invert",
            f"{at[0.0]:.2f} mm",
            "7.27 mm",
            f"{at[0.0] / 7.27:.2f}",
            "The paper's two invert values disagree with each other.",
        ),
        row(
            "Conclusions: peak displacement at 35 m",
            f"{at[35.0]:.2f} mm",
            "0.91 mm",
            f"{at[35.0] / 0.91:.2f}",
            "See the note below.",
        ),
        "",
        "### The other readings of the paper's Table 4",
        "",
        row("soil reading", "E (MPa)", "ν", "c2 (m/s)", "invert (mm)", "11 m (mm)", "35 m (mm)"),
        row("---", "---", "---", "---", "---", "---", "---"),
    ]
    for name, result in (
        ("E = 6 MPa, ν = 0.3 (default)", train),
        ("c1 = 524, c2 = 190 m/s", readings["paper_soil_wave_speeds"]),
        ("λ = 1.4 GPa, μ = 191 MPa", readings["paper_soil_lame"]),
    ):
        soil = result.scenario.soil
        d, p = result.soil.depth_m, result.soil.peak_disp_m
        lines.append(
            row(
                name,
                f"{soil.youngs_modulus / 1e6:.1f}",
                f"{soil.poisson_ratio:.3f}",
                f"{soil.s_wave_speed:.1f}",
                f"{p[0] * MM:.3f}",
                f"{np.interp(11.0, d, p) * MM:.3f}",
                f"{p[-1] * MM:.3f}",
            )
        )
    lines += ["", *model_comparison(train, moving, smooth), "", NOTES.strip(), ""]
    OUT.write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {OUT}")


def model_comparison(flat, moving, smooth) -> list[str]:
    """Section: the paper's 2D section against the 2.5D moving-load model (docs/model.md §9)."""
    scenario = moving.scenario
    tunnel, soil = scenario.tunnel, scenario.soil
    length, bending, spring = beam_on_soil_length(tunnel, soil)
    x = np.linspace(0.0, 80.0, 161)
    static = point_load_response(0.01, x, [0.0, 11.0], tunnel, soil, 32)[0].real
    depths = (0.0, 5.0, 11.0, 20.0, 35.0)
    peak = {
        name: [float(np.interp(d, r.soil.depth_m, r.soil.peak_disp_m)) * MM for d in depths]
        for name, r in (("2d", flat), ("2.5d", moving))
    }
    lines = [
        "## The 2D section against the 2.5D moving-load model (docs/model.md §9)",
        "",
        "Same vehicle–track run (`Scenario.paper()` and `Scenario.paper_2p5d()` share it), same",
        "line load q = 2F_b/L_s; the 2D model applies it to the whole tunnel at once, the 2.5D",
        "model to a lining that is a Flügge shell along the tunnel, with the load moving at",
        f"v = {scenario.train.speed:.1f} m/s (kernel at ξ = ω/v; docs/tunnel_soil_3d.md).",
        "",
        row("depth (m)", *[f"{d:g}" for d in depths]),
        row("---", *["---"] * len(depths)),
        row("2D peak displacement (mm)", *[f"{p:.2f}" for p in peak["2d"]]),
        row("2.5D peak displacement (mm)", *[f"{p:.2f}" for p in peak["2.5d"]]),
        row("2.5D / 2D", *[f"{b / a:.2f}" for a, b in zip(peak["2d"], peak["2.5d"], strict=True)]),
        row("2D, relative to the invert", *[f"{p / peak['2d'][0]:.2f}" for p in peak["2d"]]),
        row("2.5D, relative to the invert", *[f"{p / peak['2.5d'][0]:.2f}" for p in peak["2.5d"]]),
        "",
        f"**Beam on soil.** Along the tunnel the lining bends as a tube, EI = Eπa³h(1 + h²/4a²) "
        f"= {bending:.3g} N·m², on the soil's spring k = {spring / 1e6:.2f} MN/m² "
        f"({spring / soil.shear_modulus:.2f} μ; the inverse of the bare cavity's n = 1 "
        f"displacement per unit line load at the wavenumber 1/L, quasi-static). The "
        f"beam-on-soil length (4EI/k)^¼ = {length:.1f} m is the distance over which the "
        "lining spreads a load along the tunnel (a Winkler beam's deflection under a point "
        "force falls to e^(−x/L)(cos + sin)(x/L)). In the 2.5D model the quasi-static invert "
        "displacement under a point force on the invert falls to half its peak at "
        f"x = {half_width(x, static[:, 0]):.1f} m (at 11 m below: "
        f"{half_width(x, static[:, 1]):.1f} m).",
        "",
        "**What the 2D simplification does.** The 2D section loads an infinite length of "
        "tunnel with the force of one block; its static response to a line load is infinite "
        "(the n = 1 term grows like ln 1/ω), so the peak is set by how long the load lasts. "
        "In the 2.5D model each axle loads about 2L of lining, the response to a moving point "
        "force is finite, and the train's axles add up only where their spread loads overlap. "
        f"The invert peak is {peak['2.5d'][0] / peak['2d'][0]:.0%} of the 2D one. The depth "
        "decay is nearly the same in the two models here: the loaded length (the "
        f"{scenario.train.n_cars * scenario.train.car_length:.0f} m train, each axle spread "
        "over ~2L) is larger than the depths of interest, so at 0–35 m the "
        "ground still sees a long, nearly line-like load in both; the 2.5D profile decays "
        "slightly slower relative to its smaller invert value. The paper's faster decay "
        "(2.94/6.72 = 0.44 at 11 m) is not explained by the missing third dimension.",
        "",
        *irregular_rail_note(moving, smooth),
    ]
    return lines


def irregular_rail_note(rough, smooth) -> list[str]:
    """Size of the irregular rail's part of the 2.5D response: the moving-frame error's scale."""
    rows = [int(np.argmin(np.abs(rough.soil.depth_m - d))) for d in (0.0, 11.0)]
    peak = [float(smooth.soil.peak_disp_m[r]) for r in rows]
    change = [float(rough.soil.peak_disp_m[r]) / p - 1 for r, p in zip(rows, peak, strict=True)]
    part = [
        float(np.abs(rough.soil.disp_m[r] - smooth.soil.disp_m[r]).max()) / p
        for r, p in zip(rows, peak, strict=True)
    ]
    force = rough.vehicle_track.block_force_N.max() / smooth.vehicle_track.block_force_N.max() - 1
    return [
        "**Irregular rail and the moving frame.** On a smooth rail the force under every block "
        "is the monitored block's force delayed by x_j/v, and H(ω, ω/v)Q(ω) equals the direct "
        "sum over the blocks (tested: < 1 %, 0.06 % at the invert and 0.4 % at 11 m). With "
        "irregularity the dynamic part of the wheel forces moves with the wheels while it "
        "oscillates (its exact wavenumber is (ω − ω′)/v, not ω/v), so the moving-frame "
        "evaluation of the monitored block's force is an approximation for that part only. Its "
        f"size here: the class-6 irregularity changes the peak block force by {force:+.1%} and "
        f"the 2.5D peak displacement by {change[0]:+.2%} at the invert and {change[1]:+.2%} at "
        f"11 m (smooth rail: {peak[0] * MM:.3f} and {peak[1] * MM:.3f} mm); the largest "
        "difference between the rough- and smooth-rail displacement histories is "
        f"{part[0]:.1%} of the peak at the invert and {part[1]:.1%} at 11 m. The moving-frame "
        "treatment evaluates that part at a shifted wavenumber (a different spreading, not a "
        "different order of magnitude), so its error on the peaks is of this order.",
    ]


NOTES = """
## Notes

**What reproduces.** The millimetre magnitude of the paper's Fig. 11 is reproduced only by the
soft reading of Table 4 (E = 6 MPa, ν = 0.3): the stiffer readings implied by its own wave
speeds or Lamé constants give displacements 15–35 times smaller. The load spectrum is
concentrated below 30 Hz, as the paper says, and the model's sleeper-displacement pulse is
wider than the Winkler beam's, as in its Fig. 5.

**What does not, and why.** The displacement decays with depth more slowly here than in the
paper's Fig. 11 (ratio 1.2 at the invert, 1.7 at 11 m, 3.6 at 35 m). A 2D plane-strain section
under a line load responds at low frequency like ln(1/ω) (the n = 1 term), so each axle leaves
a slowly decaying tail, the response builds up along the 6.7 s passage (the peak comes near
the end of the train) and that quasi-static part falls off with depth only logarithmically.
The paper does not say how it treated the zero-frequency bin, the record length or the
harmonic count, and its soil equations carry only the P potential, which cannot satisfy both
interface conditions; each of these changes the depth decay. We keep the consistent model of
docs/model.md §7 and show, in the tests, that our peak converges in record length (zero padding)
and harmonics, rather than tune it. A true 3D (2.5D) tunnel model would spread the load along
the tunnel; the section above compares it with the 2D model.

A side effect to know when reading the time histories: constant hysteretic damping is not
causal, so the invert moves about 1–2 % of its peak before the first axle arrives.

The spectral peaks: with 22 m cars at 80 km/h the car-passing harmonics sit at multiples of
1.01 Hz, so the paper's "2, 3, 4 Hz" are the 2nd–4th of them. Which harmonics stand out is
set by the axle pattern's envelope (zeros where a multiple of the wheelbase or bogie spacing
equals a whole number of wavelengths), so it depends on the geometry the paper does not give
for certain (docs/model.md assumes the Type A dimensions); we list what our geometry gives and do
not tune it. The paper's Table 2 (track) is missing; track
values are docs/model.md's stated assumptions, which shifts every absolute force and displacement.
"""

if __name__ == "__main__":
    main()
