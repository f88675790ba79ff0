"""Shared pytest configuration: Hypothesis profiles.

``ci`` (selected when the environment has ``CI=true``) is derandomised so a CI run is
reproducible and never flakes on a lucky draw; ``dev`` (the default) explores new examples
on every run and remembers failures in the local example database. ``thorough`` is for an
occasional long local run: ``HYPOTHESIS_PROFILE=thorough pytest tests``. With
``GCU_TEST_SIZE=reduced`` (tests/_scale.py) the chosen profile runs 25 examples per test.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

from _scale import FULL

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
if not FULL:  # a reduced-size run (tests/_scale.py): fewer examples, same profile otherwise
    settings.register_profile(f"{_profile}-reduced", settings.get_profile(_profile),
                              max_examples=25)  # fmt: skip
    _profile = f"{_profile}-reduced"
settings.load_profile(_profile)
