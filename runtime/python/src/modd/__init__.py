"""MoDD runtime for Python: the link codec, publisher and subscriber clients and the SubBroker."""
