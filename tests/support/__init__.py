"""Helpers shared by the cross-component tests of several trees (tests/deploy,
tests/twodrones). A test module puts ``tests/`` on ``sys.path`` and imports
``support.loopback``."""
