"""Client helpers: the client's command methods found by what they send, an application process."""
