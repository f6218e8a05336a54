"""Load → soil: the tunnel–soil response under the invert line load (one stage of the chain).

Paper §3 and §4.2, docs/model.md §7–9; implementation notes in docs/tunnel_soil.md (2D) and
docs/tunnel_soil_3d.md (2.5D).

- ``bessel``: K₀, K₁ of complex argument and the one ratio recurrence K_{n+1}/K_n that both
  kernels use;
- ``inputs``: the lining and soil constants the kernels take, checked, and the invert load's
  Fourier coefficients;
- ``section_2d``: the paper's plane-strain section, a thin ring in a full-space per harmonic:
  :func:`invert_receptance`, the soil field and the ring's motion (§7);
- ``moving_load_2p5d``: the lining as a Flügge shell along the tunnel, loaded by
  exp(i(ωt − ξx)): :func:`receptance_2p5d` and the stresses under the invert (§9);
- ``point_load``: the point-force response of the 2.5D model, the wavenumber integral of H;
- ``kernel_sampling``: the frequencies (per output depth) at which a kernel is evaluated on a
  record's grid, and the 6-point Lagrange interpolation between them;
- ``response``: the line-load history through the chosen kernel to displacement histories at
  depth, their peaks and spectra (§8) — the *transient* response, not the permanent settlement;
- ``stresses``: the dynamic stresses and deviator under the invert per passage, from the same
  kernel evaluation, which drive the long-term stage (§10);
- ``halfspace_kernels``: plane waves in a half-space, the free-surface reflection in closed form
  in a basis regular down to ω = 0 (§16);
- ``hankel``: the adaptive Gauss–Kronrod Hankel transform from radial wavenumber to distance;
- ``halfspace``: the half-space Green's function :func:`halfspace_point_response` (Stokes +
  reflected field; Mindlin at ω = 0, Rayleigh waves at the surface);
- ``pipe_in_pipe``: the 2.5D tunnel in a half-space (the full-space tunnel's waves reflected at
  the free surface, not scattered back): the field above the axis, at the ground surface and
  the reflected field under the invert;
- ``ground_vibration``: one-third-octave bands, velocity levels re 1e-9 m/s, the ground-surface
  results of a passage;
- ``halfspace_response``: the soil stage in a half-space (under the invert and at the ground
  surface), which ``model.pipeline.run`` uses with ``tunnel.ground == "half_space"``.
"""
