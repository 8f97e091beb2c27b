"""The ground as a radar sees it: the persistent clutter field, sigma0 of ground materials,
the rough-surface mirror and the ground surface they stand on (docs/clutter.md)."""
