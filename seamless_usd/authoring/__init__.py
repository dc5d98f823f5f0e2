"""authoring step (see DESIGN.md)."""
