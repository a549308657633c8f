"""constructions."""

__all__: list[str] = []
