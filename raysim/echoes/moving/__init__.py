"""Things that move in a scene: cars traced by PO + SBR, rotating parts, moving point
scatterers and the target-ground ghosts whose end points move (docs/clutter.md)."""
