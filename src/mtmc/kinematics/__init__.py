"""mtmc.kinematics."""

__all__: list[str] = []
