"""Planning calibrations before they fly (docs/planning.md)."""
