"""Network-namespace helpers: two hosts on one LAN."""
