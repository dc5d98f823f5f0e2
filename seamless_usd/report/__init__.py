"""report step (see DESIGN.md)."""
