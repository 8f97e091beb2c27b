"""Radar description: FMCW waveform and configuration, antenna arrays."""
