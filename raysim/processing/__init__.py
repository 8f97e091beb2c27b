"""From IF frames to maps (RD, RA, AE) and the metrics measured on them."""
