"""Shared pytest configuration: test tiers (tests/helpers/tiers.py) and Hypothesis profiles.

Every collected test gets exactly one kind marker (``fast``, ``realtime``, ``subprocess``,
``netns``, ``browser``, ``tshark``, ``sitl``) and, if it cannot share the machine, ``alone``:
``pytest -m fast`` is the fast tier, ``-m "not alone"`` the parallel phase of the full run.

``ci`` (selected when the environment has ``CI=true``) is derandomised so a CI run is
reproducible and never flakes on a lucky draw; ``dev`` (the default) explores new examples
on every run and remembers failures in the local example database. ``thorough`` is for an
occasional long local run: ``HYPOTHESIS_PROFILE=thorough pytest tests``. With
``GCU_TEST_SIZE=reduced`` (tests/helpers/scale.py) the chosen profile runs 25 examples per test.
"""

from __future__ import annotations

import gc
import os

import pytest
from hypothesis import HealthCheck, settings

from helpers.scale import FULL
from helpers.tiers import ALONE, DEFAULT, FAST, HEAVY, KINDS, MARKERS, TIERS, kinds_of


def pytest_configure(config: pytest.Config) -> None:
    for name, meaning in MARKERS.items():
        config.addinivalue_line("markers", f"{name}: {meaning}")


def tier_of(item: pytest.Item) -> tuple[str, bool, bool]:
    """``(kind, alone, heavy)`` of a collected test: its own kind marker (test, class or module
    ``pytestmark``) if it has one, else its file's entry in TIERS, else the full tier."""
    own = list(dict.fromkeys(m.name for m in item.iter_markers() if m.name in KINDS))
    entry = kinds_of(TIERS.get(item.path.name, DEFAULT))
    if len(own) > 1:
        raise pytest.UsageError(f"{item.nodeid}: more than one test kind marker: {own}")
    kind = own[0] if own else next(k for k in entry if k in KINDS)
    alone = item.get_closest_marker(ALONE) is not None or (not own and ALONE in entry)
    heavy = item.get_closest_marker(HEAVY) is not None or (not own and HEAVY in entry)
    if alone and kind == FAST:
        raise pytest.UsageError(f"{item.nodeid}: a fast test cannot be {ALONE!r}")
    if heavy and kind != FAST:
        raise pytest.UsageError(f"{item.nodeid}: only a fast test can be {HEAVY!r}")
    return kind, alone, heavy


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        kind, alone, heavy = tier_of(item)
        for name, wanted in ((kind, True), (ALONE, alone), (HEAVY, heavy)):
            if wanted and item.get_closest_marker(name) is None:
                item.add_marker(name)


def pytest_collection_finish(session: pytest.Session) -> None:
    """Put what collection built out of the garbage collector's reach (``gc.freeze``, made
    for long-lived start-up objects): ~360,000 objects for ~11,400 items, which every full
    collection would walk with the event loop held (200-240 ms measured here), so a
    real-time test would measure pytest's heap instead of the library."""
    gc.collect()
    gc.freeze()


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
if not FULL:  # a reduced-size run (tests/helpers/scale.py): fewer examples, same profile otherwise
    settings.register_profile(f"{_profile}-reduced", settings.get_profile(_profile),
                              max_examples=25)  # fmt: skip
    _profile = f"{_profile}-reduced"
settings.load_profile(_profile)
