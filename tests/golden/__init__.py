"""Golden operation counts (ops.csv) and their generator (golden.py, `make golden`)."""
