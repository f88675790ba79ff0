"""Dissector helpers: tshark's view of a capture, a corpus of every packet, the comparison with
``gcu-async decode``."""
