"""The contracts between MoDD's processes and languages, written once
(docs/architecture.md, "Contracts"):

- :mod:`modd_contracts.keys`: the zenoh key expressions;
- ``schemas/``: JSON Schemas of the delivered value, the SubBroker status
  document, the plan JSON and the PubBroker's ``pubbroker.json``, loaded
  with :func:`modd_contracts.schema.load`;
- :mod:`modd_contracts.types_gen`: TypedDicts generated from those schemas
  (``python -m modd_contracts.typegen``, which also writes the TypeScript
  types and the C++ aggregation table);
- :mod:`modd_contracts.aggregations_gen`: the aggregation table, generated from
  the metamodel's ``Aggregation`` definition.

Dependency-free (standard library only), so every process can import it.
"""
