"""synthesis step (see DESIGN.md)."""
