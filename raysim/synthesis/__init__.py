"""From echo paths (delays, amplitudes) to IF frames ``[chirp, channel, sample]``."""
