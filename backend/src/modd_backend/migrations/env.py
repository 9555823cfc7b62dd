"""Alembic environment: run by :func:`modd_backend.db.migrate` with the
connection passed in ``config.attributes["connection"]``."""

from alembic import context

from modd_backend.tables import Base

config = context.config
connection = config.attributes["connection"]
context.configure(
    connection=connection,
    target_metadata=Base.metadata,
    render_as_batch=connection.dialect.name == "sqlite",
)
with context.begin_transaction():
    context.run_migrations()
