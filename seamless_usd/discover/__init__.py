"""discover step (see DESIGN.md)."""
