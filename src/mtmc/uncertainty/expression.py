"""expression."""

__all__: list[str] = []
