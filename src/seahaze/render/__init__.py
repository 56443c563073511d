"""Mitsuba-facing code: variant selection, scene assembly and render passes."""
