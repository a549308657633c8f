"""tolerance."""

__all__: list[str] = []
