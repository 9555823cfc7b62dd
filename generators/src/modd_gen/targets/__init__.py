"""One module per generated target; each exposes ``artifacts(ctx) -> list[Artifact]``."""
