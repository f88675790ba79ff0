"""Web backend example: a Starlette app owning one GCU client (needs the ``web`` extra).

The app lives in :mod:`examples.web.app` (``create_app``, ``app_from_env``); run it from
the repository root with ``python -m examples.web --sim`` (see README.md).
"""
