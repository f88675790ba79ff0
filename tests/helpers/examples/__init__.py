"""The examples' helpers: the web example's dependencies checked in one place, the app under
uvicorn."""
