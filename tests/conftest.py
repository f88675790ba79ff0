"""Shared pytest configuration: Hypothesis profiles.

``ci`` (selected when the environment has ``CI=true``) is derandomised so a CI run is
reproducible and never flakes on a lucky draw; ``dev`` (the default) explores new examples
on every run and remembers failures in the local example database. ``thorough`` is for an
occasional long local run: ``HYPOTHESIS_PROFILE=thorough pytest tests``.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=100,
    derandomize=True,
    database=None,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", max_examples=100, deadline=None)
settings.register_profile("thorough", max_examples=2000, deadline=None)

_profile = os.environ.get("HYPOTHESIS_PROFILE")
if _profile is None:
    _profile = "ci" if os.environ.get("CI", "").strip().lower() == "true" else "dev"
settings.load_profile(_profile)
