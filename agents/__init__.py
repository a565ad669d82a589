"""roller-gym agents."""
