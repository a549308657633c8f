"""mtmc.uncertainty."""

__all__: list[str] = []
