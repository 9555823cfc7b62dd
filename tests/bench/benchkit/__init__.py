"""Shared pieces of the peer benchmarks (tests/bench/bench_*.py and the smoke test): the
scenarios as loads, processes and their footprint, tshark captures, and one runner per
system compared (this project's link, Mosquitto, zenoh downsampling)."""
