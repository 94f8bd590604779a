"""Tests of the native tracer `dacrt` against an independent float64 brute-force reference."""
