"""The render layer: a validated spec and its geometry in, radiance and per-pixel passes out.

* :mod:`~seahaze.render.engine` — :func:`render_scene`, a whole scene in memory (no file I/O).
* :mod:`~seahaze.render.scene` — the Mitsuba scene of a spec's geometry and haze medium.
* :mod:`~seahaze.render.passes` — geometry, clean, and the ``reference``/``asm`` haze passes.
* :mod:`~seahaze.render.levels` — one entry point for the hazy levels of every mode.
* :mod:`~seahaze.render.physical` — the ``physical`` mode: tables and both passes, run.
* :mod:`~seahaze.render.haze_integrator` — its integrators' shared base and the camera pass
  (import once a Mitsuba variant is set); :mod:`~seahaze.render.vessel_light` the second pass.
* :mod:`~seahaze.render.pass_levels` — a pass's levels as kernel parameters, asking the medium.
* :mod:`~seahaze.render.estimator` — the ``physical`` estimator's settings.
* :mod:`~seahaze.render.diffuse_table` — its plane-parallel diffuse-field tables.
* :mod:`~seahaze.render.jit_haze` — the phase function in drjit, and kernel-input rules.
* :mod:`~seahaze.render.variant` — which Mitsuba variant runs here.

The haze itself is :mod:`seahaze.medium`'s: every module here asks it.
"""
