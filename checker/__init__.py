"""cablecheck geometry."""
