"""mtmc.geometry."""

__all__: list[str] = []
