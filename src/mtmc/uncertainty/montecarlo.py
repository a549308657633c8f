"""montecarlo."""

__all__: list[str] = []
