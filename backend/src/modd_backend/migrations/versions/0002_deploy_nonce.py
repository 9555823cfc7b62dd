"""deployments: the signed request's nonce, which the drone's status names
while it runs that deployment (the key of reconciliation, docs/backend.md)

Revision ID: 0002
Revises: 0001
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0002"
down_revision: str | None = "0001"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("deployments") as batch:
        batch.add_column(sa.Column("nonce", sa.String(128), nullable=True))
        batch.create_index("ix_deployments_nonce", ["nonce"])
        batch.create_index("ix_deployments_status", ["status"])


def downgrade() -> None:
    with op.batch_alter_table("deployments") as batch:
        batch.drop_index("ix_deployments_status")
        batch.drop_index("ix_deployments_nonce")
        batch.drop_column("nonce")
