"""fits."""

__all__: list[str] = []
