"""imaging step (see DESIGN.md)."""
