"""Benchmarks of chainrun against its peers (``make bench``; see README.md here)."""
