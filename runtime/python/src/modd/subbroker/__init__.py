"""The base-station SubBroker (docs/subbroker.md).

Light on purpose: ``import modd.subbroker`` loads neither zenoh nor the
planner; :class:`~modd.subbroker.broker.SubBroker` lives in ``broker``.

>>> from modd.subbroker.broker import SubBroker            # doctest: +SKIP
>>> from modd.subbroker.config import load_config          # doctest: +SKIP
>>> SubBroker(load_config("subbroker.toml")).start()       # doctest: +SKIP
"""
