"""pipeline step (see DESIGN.md)."""
