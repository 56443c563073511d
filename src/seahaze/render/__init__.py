"""The render layer: a validated spec and its geometry in, radiance and per-pixel passes out.

* :mod:`~seahaze.render.engine` — :func:`render_scene`, a whole scene in memory (no file I/O).
* :mod:`~seahaze.render.scene` — the Mitsuba scene of a spec's geometry.
* :mod:`~seahaze.render.passes` — geometry, clean, and the ``reference``/``asm`` haze passes.
* :mod:`~seahaze.render.physical` — the ``physical`` mode's haze integrator.
* :mod:`~seahaze.render.diffuse_table` — its plane-parallel diffuse-field table.
* :mod:`~seahaze.render.levels` — one entry point for the hazy levels of every mode.
* :mod:`~seahaze.render.jit_haze` — drjit copies of :mod:`seahaze.haze` for the integrator.
* :mod:`~seahaze.render.variant` — which Mitsuba variant runs here.
"""
