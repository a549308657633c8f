"""primitives."""

__all__: list[str] = []
