"""hooks step (see DESIGN.md)."""
