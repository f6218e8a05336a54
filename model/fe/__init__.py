"""The paper's elastic–plastic finite-element check of the section, built as an OpenSees model.

docs/model.md §12; the study and the results are in docs/fe_section.md. A plane-strain section
(1 m thick slice, y up, origin on the tunnel axis) under the line-load history of the pipeline,
with elastic or undrained Mohr–Coulomb soil, set beside the analytical profile of
``model.soil.response`` and the long-term stage. The model is OpenSees' (quads, J2
plasticity, beams, zero-length springs and dashpots); it is solved by this package's own
assembly and Numba kernel by default, or by OpenSeesPy itself, an optional extra (``fe``).

- ``inputs``: what the FE takes from the scenario and the load: the load band, Rayleigh
  damping, the Drucker–Prager match of Mohr–Coulomb, the load averaged per FE step, and the
  geostatic stress field;
- ``mesh``: :class:`FEMesh` (the user's mesh and boundary settings) and the structured
  half-annulus mesh with its consistent nodal loads;
- ``build``: the OpenSees model: soil quads, lining beams, viscous–spring boundary, the
  gravity stage with K0 and the analyses (``OpenSeesSection``); whether OpenSeesPy can be
  loaded here (``fe_unavailable_reason``);
- ``native``: the same model assembled with SciPy and stepped here (``NativeSection``, the
  default engine);
- ``analysis``: :func:`run_fe` (passages, peaks and permanent displacements),
  :func:`gravity_state`, and the analytical profile on the same load;
- ``store``: :class:`FEResult`, stored in ``.npz`` files keyed by the scenario;
- ``cli``: ``python -m model fe``.
"""
