"""Charts drawn from measured results (one PNG per chart module)."""
