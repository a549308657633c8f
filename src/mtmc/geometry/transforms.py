"""Homogeneous transforms and rotations, batched."""

__all__: list[str] = []
