"""Reports: result frames (frames.py), figures (figures.py), tables and named tables (tables.py), and
the pages of `rast5d report` (pages.py)."""
