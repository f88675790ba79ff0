"""The suite's shared modules, imported by name from every test folder (``pythonpath`` in
pyproject.toml puts tests/ on the path): ``from helpers.session.vtime import Rig``.

A folder per layer, named as the test folder whose layer the module serves (the simulator's
process is in ``sim/`` though client, CLI and bridge tests start it too); beside them the
suite's configuration: :mod:`helpers.tiers` (each test file's kind) and
:mod:`helpers.scale` (``GCU_TEST_SIZE``). CONTRIBUTING.md, "Helpers", has the table."""
