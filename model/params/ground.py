"""The tunnel lining and the soil around it."""

from __future__ import annotations

import math

import param

from model.params.quantities import Choice, _q

# Thin-ring limit on the lining, h/a (Scenario.validate): thin-ring theory neglects shear
# deformation and the stress variation through the thickness, relative errors of order (h/a)²
# (~4 % at 0.2); tunnel linings have h/a ≈ 0.05–0.15 (the paper's 0.105).
THIN_RING_MAX_RATIO = 0.2


class Tunnel(param.Parameterized):
    """Concrete lining as a thin elastic ring in plane strain (paper Table 3, corrected).

    Used by ``model.soil.inputs.ring_constants`` (a, m, K, D of the 2D ring and the 2.5D shell);
    the axis depth by the static stress state of the long-term stage and, with ``ground`` =
    "half_space", by the tunnel in a half-space (``model.soil.pipe_in_pipe``).
    Besides the bounds, ``Scenario.validate`` requires a thin ring, h/a ≤ ``THIN_RING_MAX_RATIO``.
    """

    inner_radius = _q(
        2.7,
        (1.0, 10.0),
        (2.0, 4.0),
        "Lining inner radius (m)",
        "Inner radius of the lining (paper Table 3); a = inner radius + h/2 in "
        "model.soil.inputs.ring_constants. Bounds 1–10 m: a small service tunnel to a large "
        "two-track tunnel.",
    )
    thickness = _q(
        0.30,
        (0.05, 1.5),
        (0.2, 0.6),
        "Lining thickness (m)",
        "Lining thickness h (the paper's '30 m' is a typo for 0.30 m, docs/model.md §7), in "
        "model.soil.inputs.ring_constants (m = ρh, K, D). Bounds 0.05–1.5 m; with "
        "Scenario.validate the thin-ring limit h/a ≤ 0.2.",
    )
    youngs_modulus = _q(
        3.45e10,
        (1e9, 2.5e11),
        (1e10, 5e10),
        "Lining Young's modulus (Pa)",
        "Young's modulus E_t of the lining (paper Table 3), in K = E_t h/(1 − ν_t²) and D of "
        "model.soil.inputs.ring_constants. Bounds 1–250 GPa: jointed masonry or cracked "
        "concrete to a steel lining.",
    )
    poisson_ratio = _q(
        0.17,
        (0.0, 0.45),
        (0.1, 0.3),
        "Lining Poisson's ratio (-)",
        "Poisson's ratio ν_t of the lining (paper Table 3), in K and D of "
        "model.soil.inputs.ring_constants. Bounds 0–0.45: lining materials (concrete 0.15–0.2, "
        "steel 0.3).",
    )
    density = _q(
        2450.0,
        (1000.0, 8000.0),
        (2000.0, 2800.0),
        "Lining density (kg/m³)",
        "Density ρ_t of the lining (paper Table 3), in the ring mass m = ρ_t h of "
        "model.soil.inputs.ring_constants. Bounds 1000–8000 kg/m³: lightweight concrete to "
        "steel.",
    )
    axis_depth = _q(
        15.0,
        (0, 200),
        (8.0, 40.0),
        "Tunnel axis depth (m)",
        "Depth of the tunnel axis below the ground surface, H_t, for the static stress state in "
        "model.longterm.geostatic (and the FE gravity stage, model.fe.inputs.geostatic) and, "
        "with ground = half_space, the tunnel's distance to the free surface in "
        "model.soil.pipe_in_pipe; the paper gives none, 15 m is assumed. Bounds (0, 200] m; "
        "Scenario.validate requires the lining below the ground surface.",
        (False, True),
    )

    model = Choice(
        default="2d",
        objects=["2d", "2.5d"],
        label="Tunnel–soil model",
        doc="'2d': the paper's plane-strain section (ring in soil), the load of one block spread "
        "over one block spacing on the whole tunnel at once; '2.5d': the lining as a cylindrical "
        "shell infinite along the tunnel, loaded by the moving train (kernel at ξ = ω/v). "
        "Dispatched by the soil stage of model.pipeline.run.",
    )

    ground = Choice(
        default="full_space",
        objects=["full_space", "half_space"],
        label="Ground",
        doc="'full_space': the soil surrounds the tunnel on every side (the paper's model, no "
        "ground surface); 'half_space': the soil ends at a free ground surface axis_depth above "
        "the tunnel axis (pipe-in-pipe method, model.soil.pipe_in_pipe; docs/halfspace.md), "
        "which also gives the vibration at the ground surface. Needs model = '2.5d' "
        "(Scenario.validate).",
    )

    @property
    def ring_radius(self) -> float:
        """Radius of the ring's middle surface a = inner radius + h/2 (m)."""
        return self.inner_radius + 0.5 * self.thickness

    @property
    def extensional_stiffness(self) -> float:
        """Plane-strain membrane stiffness K = Eh/(1 − ν²) (N/m)."""
        return self.youngs_modulus * self.thickness / (1.0 - self.poisson_ratio**2)

    @property
    def bending_stiffness(self) -> float:
        """Plane-strain bending stiffness D = Eh³/(12(1 − ν²)) (N·m)."""
        return self.extensional_stiffness * self.thickness**2 / 12.0


class Soil(param.Parameterized):
    """Homogeneous, isotropic, hysteretically damped elastic full-space (paper Table 4).

    Primary inputs are E, ν, ρ and the loss factors; wave speeds and Lamé constants are derived.
    The default E = 6 MPa, ν = 0.3 is the only reading of the self-inconsistent Table 4 that
    reproduces the paper's millimetre magnitudes (docs/model.md §7); the others are presets. Used by
    ``model.soil.inputs.soil_constants`` (μ*, λ*, ρ) and, for the record tail,
    ``model.soil.response.soil_response``.
    """

    youngs_modulus = _q(
        6e6,
        (1e6, 1e11),
        (1e6, 1e8),
        "Soil Young's modulus (Pa)",
        "Young's modulus E_s of the soil (paper Table 4), in μ, λ of "
        "model.soil.inputs.soil_constants. Bounds 1 MPa–100 GPa: a very soft clay to sound "
        "rock. Below ~1 MPa the small-strain elastic model is meaningless (a passing train "
        "would fail such ground) and its displacement profile stops decreasing with depth.",
    )
    poisson_ratio = _q(
        0.3,
        (0.0, 0.49),
        (0.1, 0.49),
        "Soil Poisson's ratio (-)",
        "Poisson's ratio ν_s of the soil (paper Table 4), in λ = 2νμ/(1 − 2ν) of "
        "model.soil.inputs.soil_constants. Bounds 0–0.49: at 0.5 the P-wave speed is "
        "infinite (incompressible soil).",
    )
    density = _q(
        1800.0,
        (1000.0, 3000.0),
        (1400.0, 2200.0),
        "Soil density (kg/m³)",
        "Soil density ρ_s (assumed typical of Nanjing soft clay; not in Table 4), in "
        "model.soil.inputs.soil_constants and the wave speeds. Bounds 1000–3000 kg/m³: "
        "organic soils to dense rock.",
    )
    shear_loss_factor = _q(
        0.06,
        (0.0, 0.4),
        (0.0, 0.3),
        "Shear loss factor η_G (-)",
        "Hysteretic shear loss factor η_G: μ* = μ(1 + iη_G) in "
        "model.soil.inputs.soil_constants (paper Table 4). Bounds 0–0.4: a damping ratio "
        "η/2 up to 20 %; more is not small-strain behaviour, and the non-causal response of "
        "hysteretic damping grows with η.",
    )
    bulk_loss_factor = _q(
        0.0,
        (0.0, 0.4),
        (0.0, 0.3),
        "Bulk loss factor η_K (-)",
        "Hysteretic bulk loss factor η_K: K* = K(1 + iη_K) in "
        "model.soil.inputs.soil_constants (paper Table 4). Bounds 0–0.4 as η_G.",
    )

    @classmethod
    def from_lame(
        cls, lame_lambda: float, shear_modulus: float, density: float, **overrides
    ) -> Soil:
        """Soil from its Lamé constants λ, μ (Pa) and density (kg/m³)."""
        youngs = (
            shear_modulus * (3 * lame_lambda + 2 * shear_modulus) / (lame_lambda + shear_modulus)
        )
        poisson = lame_lambda / (2 * (lame_lambda + shear_modulus))
        return cls(youngs_modulus=youngs, poisson_ratio=poisson, density=density, **overrides)

    @classmethod
    def from_wave_speeds(
        cls, p_wave_speed: float, s_wave_speed: float, density: float, **overrides
    ) -> Soil:
        """Soil from its P- and S-wave speeds c1, c2 (m/s) and density (kg/m³)."""
        shear = density * s_wave_speed**2
        lame_lambda = density * p_wave_speed**2 - 2 * shear
        return cls.from_lame(lame_lambda, shear, density, **overrides)

    @property
    def shear_modulus(self) -> float:
        """Lamé μ = E / (2(1 + ν)) (Pa)."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def lame_lambda(self) -> float:
        """Lamé λ = 2νμ / (1 − 2ν) (Pa)."""
        return 2.0 * self.poisson_ratio * self.shear_modulus / (1.0 - 2.0 * self.poisson_ratio)

    @property
    def bulk_modulus(self) -> float:
        """Bulk modulus K = λ + 2μ/3 (Pa)."""
        return self.lame_lambda + 2.0 * self.shear_modulus / 3.0

    @property
    def p_wave_speed(self) -> float:
        """Compression wave speed c1 = √((λ + 2μ)/ρ) (m/s), undamped."""
        return math.sqrt((self.lame_lambda + 2.0 * self.shear_modulus) / self.density)

    @property
    def s_wave_speed(self) -> float:
        """Shear wave speed c2 = √(μ/ρ) (m/s), undamped."""
        return math.sqrt(self.shear_modulus / self.density)
