"""The MoDD launcher: ``modd up`` (:mod:`modd_launch.up`), which generates a
model's configs (``modd_gen``) and runs the runtime's processes (``modd``) with
them. The runtime itself never imports the generators
(metamodel/tests/test_import_cycles.py)."""
