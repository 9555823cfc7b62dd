"""MCAP archives of the PubBroker, read back on the base station:
:mod:`.scan` (every complete record of a file, crashed or not),
:mod:`.recover` (rewrite a crashed file with its summary and index) and
:mod:`.info` (topics, counts, time range, gaps). ``modd archive`` runs them
(:mod:`.cli`)."""
