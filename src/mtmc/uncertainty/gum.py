"""gum."""

__all__: list[str] = []
