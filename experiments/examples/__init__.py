"""Example applications of the engine beyond image rendering."""
