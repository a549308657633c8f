"""Batched geometric constructions: points, vectors, lines, planes, circles and frames.

These are the operations of Stryczek's measurement graph (the transitions
``middle``, ``vector``, ``unit_v``, ``displace``, ``line``, ``plane``, ``point``,
``project``, ``per_proj``, ``distance``, ``angle``, ``circle``, ``frame``). Every
function computes a whole batch of ``M`` trials in one pass: points and vectors are
``(M, 3)``, scalars ``(M,)``, frames ``(M, 4, 4)``. Each point or vector argument may
also be a single ``(3,)`` point (a batch of one), and a batch of one broadcasts against
a batch of ``M`` (a nominal point with ``M`` sampled ones); the result has the common
batch size. Outputs are float64, lengths in mm, angles in rad.

Degenerate input raises :class:`mtmc.errors.DegenerateGeometryError` naming the case
and how many trials are affected. The test is relative, with tolerance
:data:`mtmc.geometry.checks.RTOL` (``1e-10``): e.g. three points are collinear when
``|(b - a) × (c - a)| <= RTOL |b - a| |c - a|`` (the sine of the angle at ``a``). NaN
coordinates are not checked here: they propagate to NaN results.

Where the code departs from the printed formulas of Stryczek
------------------------------------------------------------
Eq. 22 prints the second component of the normal ``V_12 × V_13`` as
``J_0 = a_x b_z - b_x a_z``; the cofactor expansion of the determinant (20) gives
``J_0 = a_z b_x - a_x b_z`` (the opposite sign). :func:`plane_from_points` uses the
correct cross product, so the normal is right-handed with respect to ``a, b, c`` as
the text says.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.geometry.checks import (
    RTOL,
    batch_size,
    check_points,
    check_scalars,
    check_vectors,
    degenerate,
)
from mtmc.geometry.primitives import Circle, Line, Plane
from mtmc.geometry.vec import cross as _cross

__all__ = [
    "angle_between",
    "circle_from_points",
    "displace",
    "distance_point_line",
    "distance_point_plane",
    "distance_point_point",
    "foot_on_line",
    "frame_from_plane_line_point",
    "intersect_line_plane",
    "line_from_planes",
    "line_from_point_direction",
    "line_from_points",
    "middle",
    "normal_plane_basis",
    "plane_from_point_normal",
    "plane_from_points",
    "project_point_plane",
    "unit_vector",
    "vector",
]


def _dot(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    out: NDArray[np.float64] = np.einsum("...i,...i->...", a, b)
    return out


def _norm(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.sqrt(_dot(a, a))


def _pair(
    a: npt.ArrayLike, b: npt.ArrayLike, na: str, nb: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    aa = check_points(a, na)
    bb = check_points(b, nb)
    batch_size(**{na: aa, nb: bb})
    return aa, bb


def middle(a: npt.ArrayLike, b: npt.ArrayLike) -> NDArray[np.float64]:
    """The midpoint of the segment from ``a`` to ``b`` (transition ``middle``, Stryczek).

    ``m = (a + b) / 2``.

    Parameters
    ----------
    a, b : array_like, shape (M, 3) or (3,)
        The end points, mm.

    Returns
    -------
    ndarray, shape (M, 3)
        The midpoints, mm.

    Examples
    --------
    >>> middle([0, 0, 0], [[2, 4, 6], [0, 0, 2]])
    array([[1., 2., 3.],
           [0., 0., 1.]])
    """
    aa, bb = _pair(a, b, "a", "b")
    return 0.5 * (aa + bb)


def vector(a: npt.ArrayLike, b: npt.ArrayLike) -> NDArray[np.float64]:
    """The vector from ``a`` to ``b``, ``b - a`` (transition ``vector``, Stryczek).

    Parameters
    ----------
    a, b : array_like, shape (M, 3) or (3,)
        Start and end points, mm.

    Returns
    -------
    ndarray, shape (M, 3)
        The components of the segment, mm.

    Examples
    --------
    >>> vector([1, 1, 1], [2, 3, 4])
    array([[1., 2., 3.]])
    """
    aa, bb = _pair(a, b, "a", "b")
    return bb - aa


def unit_vector(v: npt.ArrayLike) -> NDArray[np.float64]:
    """The unit vector ``v / |v|`` (transition ``unit_v``, Stryczek).

    Parameters
    ----------
    v : array_like, shape (M, 3) or (3,)
        The vectors.

    Returns
    -------
    ndarray, shape (M, 3)
        The unit vectors (direction cosines).

    Raises
    ------
    DegenerateGeometryError
        If a vector has zero length (there is no scale to make this test relative:
        exactly zero, or a length that underflows to zero).

    Examples
    --------
    >>> unit_vector([3, 0, 4])
    array([[0.6, 0. , 0.8]])
    """
    vv = check_vectors(v, "v")
    n = _norm(vv)
    degenerate(n <= 0.0, "the vector has zero length", "a non-zero vector", "v")
    return vv / n[:, None]


def displace(
    p: npt.ArrayLike, v: npt.ArrayLike, length: npt.ArrayLike | None = None
) -> NDArray[np.float64]:
    """Displace points by vectors (transition ``displace``, Stryczek).

    ``p + v``, or, when ``length`` is given, ``p + length * v / |v|`` (a displacement
    by a constant such as Stryczek's ``r_2``, the height of the ball centre above the
    rotary table, along a direction).

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        The points, mm.
    v : array_like, shape (M, 3) or (3,)
        The displacements, mm (or directions, when ``length`` is given).
    length : array_like, shape (M,) or (), optional
        The signed length of the displacement along ``v``, mm.

    Returns
    -------
    ndarray, shape (M, 3)
        The displaced points, mm.

    Raises
    ------
    DegenerateGeometryError
        If ``length`` is given and a ``v`` has zero length.

    Examples
    --------
    >>> displace([1, 2, 3], [0, 0, 1])
    array([[1., 2., 4.]])
    >>> displace([1, 2, 3], [0, 0, 5], length=-2.0)
    array([[1., 2., 1.]])
    """
    pp, vv = _pair(p, v, "p", "v")
    if length is None:
        return pp + vv
    ll = check_scalars(length, "length")
    batch_size(p=pp, v=vv, length=ll)
    return pp + ll[:, None] * unit_vector(vv)


def line_from_points(a: npt.ArrayLike, b: npt.ArrayLike) -> Line:
    """The line through two points, directed from ``a`` to ``b`` (transition ``line``).

    Parameters
    ----------
    a, b : array_like, shape (M, 3) or (3,)
        Two points of each line, mm.

    Returns
    -------
    Line
        ``Line(point=a, direction=(b - a) / |b - a|)``.

    Raises
    ------
    DegenerateGeometryError
        If the points coincide: ``|b - a| <= RTOL max(|a|, |b|)``.

    Examples
    --------
    >>> line_from_points([1, 0, 0], [1, 0, 2]).direction
    array([[0., 0., 1.]])
    """
    aa, bb = _pair(a, b, "a", "b")
    d = bb - aa
    dn = _norm(d)
    scale = np.maximum(_norm(aa), _norm(bb))
    degenerate(dn <= RTOL * scale, "the two points coincide", "two distinct points", "b")
    return Line(aa, d / dn[:, None])


def line_from_point_direction(p: npt.ArrayLike, d: npt.ArrayLike) -> Line:
    """The line through ``p`` along ``d`` (normalised).

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        A point on each line, mm.
    d : array_like, shape (M, 3) or (3,)
        The directions (any non-zero length).

    Returns
    -------
    Line
        The lines.

    Raises
    ------
    DegenerateGeometryError
        If a direction has zero length.
    """
    pp, dd = _pair(p, d, "p", "d")
    return Line(pp, dd)


def line_from_planes(p1: Plane, p2: Plane) -> Line:
    """The line of intersection of two planes (transition ``line``, second variant).

    With unit normals ``n1``, ``n2`` and a reference point ``x0`` (the midpoint of the
    two planes' points), the direction is ``d = n1 × n2`` and the point is the point of
    the line closest to ``x0``:
    ``x = x0 + (h1 (n2 × d) + h2 (d × n1)) / |d|^2`` with ``h_k = n_k · (P_k - x0)``
    (it satisfies both plane equations because ``n1 · (n2 × d) = n2 · (d × n1) = |d|^2``).

    Parameters
    ----------
    p1, p2 : Plane
        The planes (batches of ``M`` or of one).

    Returns
    -------
    Line
        The intersection lines, directed along ``n1 × n2``.

    Raises
    ------
    DegenerateGeometryError
        If the planes are parallel: ``|n1 × n2| <= RTOL``.

    Examples
    --------
    >>> line = line_from_planes(Plane([0, 0, 1], [0, 0, 1]), Plane([2, 0, 0], [1, 0, 0]))
    >>> line.point, line.direction
    (array([[2., 0., 1.]]), array([[0., 1., 0.]]))
    """
    batch_size(p1=p1.point, p2=p2.point)
    n1, n2 = p1.normal, p2.normal
    d = _cross(n1, n2)
    dd = _dot(d, d)
    degenerate(dd <= RTOL**2, "the two planes are parallel", "two non-parallel planes", "p2")
    x0 = 0.5 * (p1.point + p2.point)
    h1 = _dot(n1, p1.point - x0)
    h2 = _dot(n2, p2.point - x0)
    x = x0 + (h1[:, None] * _cross(n2, d) + h2[:, None] * _cross(d, n1)) / dd[:, None]
    return Line(x, d)


def plane_from_points(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> Plane:
    """The plane through three points (transition ``plane``, Stryczek eqs. 20-29).

    The normal is ``V_12 × V_13 / |V_12 × V_13|`` with ``V_12 = b - a`` and
    ``V_13 = c - a`` (right-handed with respect to ``a, b, c``); the plane's point is
    ``a``, so its offset is ``D = -n · a`` (eq. 29). Eq. 22 is printed with the wrong
    sign; the code uses the true cross product (see the module notes).

    Parameters
    ----------
    a, b, c : array_like, shape (M, 3) or (3,)
        Three points on each plane, mm.

    Returns
    -------
    Plane
        The planes.

    Raises
    ------
    DegenerateGeometryError
        If the points are collinear (or two coincide):
        ``|V_12 × V_13| <= RTOL |V_12| |V_13|``.

    Examples
    --------
    >>> plane_from_points([0, 0, 1], [1, 0, 1], [0, 1, 1]).normal
    array([[0., 0., 1.]])
    """
    aa = check_points(a, "a")
    bb = check_points(b, "b")
    cc = check_points(c, "c")
    m = batch_size(a=aa, b=bb, c=cc)
    u = bb - aa
    v = cc - aa
    n = _cross(u, v)
    nn = _norm(n)
    degenerate(
        nn <= RTOL * _norm(u) * _norm(v),
        "the three points are collinear",
        "three non-collinear points",
        "c",
    )
    return Plane(np.broadcast_to(aa, (m, 3)), n / nn[:, None])


def plane_from_point_normal(p: npt.ArrayLike, n: npt.ArrayLike) -> Plane:
    """The plane through ``p`` with normal ``n`` (normalised).

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        A point on each plane, mm.
    n : array_like, shape (M, 3) or (3,)
        The normals (any non-zero length), e.g. the direction of a line perpendicular
        to the plane (the alternative ``plane`` transition of Stryczek).

    Returns
    -------
    Plane
        The planes.

    Raises
    ------
    DegenerateGeometryError
        If a normal has zero length.
    """
    pp, nn = _pair(p, n, "p", "n")
    return Plane(pp, nn)


def intersect_line_plane(line: Line, plane: Plane) -> NDArray[np.float64]:
    """The point where a line meets a plane (transition ``point``, Stryczek; eq. 30).

    ``x = L0 + t d`` with ``t = n · (P0 - L0) / (n · d)``.

    Parameters
    ----------
    line : Line
        The lines (point ``L0``, unit direction ``d``).
    plane : Plane
        The planes (point ``P0``, unit normal ``n``).

    Returns
    -------
    ndarray, shape (M, 3)
        The intersection points, mm.

    Raises
    ------
    DegenerateGeometryError
        If a line is parallel to its plane: ``|n · d| <= RTOL``.

    Examples
    --------
    >>> intersect_line_plane(Line([1, 2, 0], [0, 0, 1]), Plane([0, 0, 5], [0, 0, 1]))
    array([[1., 2., 5.]])
    """
    batch_size(line=line.point, plane=plane.point)
    nd = _dot(plane.normal, line.direction)
    degenerate(
        np.abs(nd) <= RTOL,
        "the line is parallel to the plane",
        "a line not parallel to the plane",
        "line",
    )
    t = _dot(plane.normal, plane.point - line.point) / nd
    return line.point + t[:, None] * line.direction


def project_point_plane(p: npt.ArrayLike, plane: Plane) -> NDArray[np.float64]:
    """The orthogonal projection of points on planes (transition ``project``).

    ``x = p - (n · (p - P0)) n``.

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        The points, mm.
    plane : Plane
        The planes.

    Returns
    -------
    ndarray, shape (M, 3)
        The projected points, mm.

    Examples
    --------
    >>> project_point_plane([1, 2, 3], Plane([0, 0, 1], [0, 0, 1]))
    array([[1., 2., 1.]])
    """
    pp = check_points(p, "p")
    batch_size(p=pp, plane=plane.point)
    s = _dot(plane.normal, pp - plane.point)
    return pp - s[:, None] * plane.normal


def foot_on_line(p: npt.ArrayLike, line: Line) -> NDArray[np.float64]:
    """The foot of the perpendicular from points to lines (transition ``per_proj``).

    ``x = L0 + ((p - L0) · d) d``; ``p - x`` is perpendicular to ``d``.

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        The points, mm.
    line : Line
        The lines.

    Returns
    -------
    ndarray, shape (M, 3)
        The feet of the perpendiculars, mm.

    Examples
    --------
    >>> foot_on_line([3, 4, 5], Line([0, 0, 0], [1, 0, 0]))
    array([[3., 0., 0.]])
    """
    pp = check_points(p, "p")
    batch_size(p=pp, line=line.point)
    t = _dot(pp - line.point, line.direction)
    return line.point + t[:, None] * line.direction


def distance_point_point(a: npt.ArrayLike, b: npt.ArrayLike) -> NDArray[np.float64]:
    """The distance ``|b - a|`` between points (transition ``distance``).

    Parameters
    ----------
    a, b : array_like, shape (M, 3) or (3,)
        The points, mm.

    Returns
    -------
    ndarray, shape (M,)
        The distances, mm.

    Examples
    --------
    >>> distance_point_point([0, 0, 0], [3, 4, 12])
    array([13.])
    """
    aa, bb = _pair(a, b, "a", "b")
    return _norm(bb - aa)


def distance_point_line(p: npt.ArrayLike, line: Line) -> NDArray[np.float64]:
    """The distance from points to lines, ``|(p - L0) × d|`` (``d`` unit).

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        The points, mm.
    line : Line
        The lines.

    Returns
    -------
    ndarray, shape (M,)
        The distances, mm, ``>= 0``.

    Examples
    --------
    >>> distance_point_line([3, 4, 0], Line([0, 0, 0], [1, 0, 0]))
    array([4.])
    """
    pp = check_points(p, "p")
    batch_size(p=pp, line=line.point)
    return _norm(_cross(pp - line.point, line.direction))


def distance_point_plane(p: npt.ArrayLike, plane: Plane) -> NDArray[np.float64]:
    """The signed distance from points to planes, ``n · (p - P0)``.

    Positive on the side the normal points to.

    Parameters
    ----------
    p : array_like, shape (M, 3) or (3,)
        The points, mm.
    plane : Plane
        The planes.

    Returns
    -------
    ndarray, shape (M,)
        The signed distances, mm.

    Examples
    --------
    >>> distance_point_plane([[0, 0, 3], [5, 5, -1]], Plane([0, 0, 1], [0, 0, 1]))
    array([ 2., -2.])
    """
    pp = check_points(p, "p")
    batch_size(p=pp, plane=plane.point)
    return _dot(plane.normal, pp - plane.point)


def angle_between(u: npt.ArrayLike, v: npt.ArrayLike) -> NDArray[np.float64]:
    """The angle between two vectors, in ``[0, π]`` rad (transition ``angle``).

    Computed as ``atan2(|u × v|, u · v)``, accurate also for nearly parallel vectors
    (where ``arccos`` of the normalised dot product loses half the digits).

    Parameters
    ----------
    u, v : array_like, shape (M, 3) or (3,)
        The vectors (any non-zero length).

    Returns
    -------
    ndarray, shape (M,)
        The angles, rad.

    Raises
    ------
    DegenerateGeometryError
        If a vector has zero length.

    Examples
    --------
    >>> import numpy as np
    >>> np.degrees(angle_between([1, 0, 0], [[1, 1, 0], [-1, 0, 0]]))
    array([ 45., 180.])
    """
    uu, vv = _pair(u, v, "u", "v")
    degenerate(_norm(uu) <= 0.0, "the vector has zero length", "a non-zero vector", "u")
    degenerate(_norm(vv) <= 0.0, "the vector has zero length", "a non-zero vector", "v")
    return np.arctan2(_norm(_cross(uu, vv)), _dot(uu, vv))


def circle_from_points(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> Circle:
    """The circle through three points (transition ``circle``, Stryczek, Fig. 7-10).

    With ``u = b - a``, ``v = c - a`` and ``w = u × v``, the centre is
    ``a + ((|u|^2 v - |v|^2 u) × w) / (2 |w|^2)`` (equidistant from the three points and
    in their plane), the radius its distance to ``a`` and the normal ``w / |w|``
    (right-handed with respect to ``a, b, c``, like :func:`plane_from_points`).

    Parameters
    ----------
    a, b, c : array_like, shape (M, 3) or (3,)
        Three points on each circle, mm.

    Returns
    -------
    Circle
        The circles.

    Raises
    ------
    DegenerateGeometryError
        If the points are collinear: ``|u × v| <= RTOL |u| |v|``.

    Examples
    --------
    >>> circ = circle_from_points([1, 0, 0], [0, 1, 0], [-1, 0, 0])
    >>> circ.centre, circ.normal, circ.radius
    (array([[0., 0., 0.]]), array([[0., 0., 1.]]), array([1.]))
    """
    aa = check_points(a, "a")
    bb = check_points(b, "b")
    cc = check_points(c, "c")
    batch_size(a=aa, b=bb, c=cc)
    u = bb - aa
    v = cc - aa
    w = _cross(u, v)
    ww = _dot(w, w)
    uu = _dot(u, u)
    vv = _dot(v, v)
    degenerate(
        ww <= RTOL**2 * uu * vv,
        "the three points are collinear",
        "three non-collinear points",
        "c",
    )
    rel = _cross(uu[:, None] * v - vv[:, None] * u, w) / (2.0 * ww[:, None])
    return Circle(aa + rel, w, _norm(rel))


def frame_from_plane_line_point(
    plane: Plane, line: Line, point: npt.ArrayLike
) -> NDArray[np.float64]:
    """A coordinate frame from a plane, a line and a point (transition ``frame``).

    The 3-2-1 alignment of a workpiece (Stryczek): the plane fixes three degrees of
    freedom (a translation along its normal and two rotations), the line two (the
    rotation about the normal and a translation across the line, in the plane), the
    point one (the translation along the line). Convention:

    - z-axis: the plane's normal ``n``;
    - x-axis: the line's direction projected on the plane,
      ``x = (d - (d · n) n) / |d - (d · n) n|``;
    - y-axis: ``y = z × x`` (right-handed);
    - origin: on the line projected in the plane, where the plane through the point
      perpendicular to that line cuts it: with ``q`` the projection of the line's point
      ``l`` on the plane, ``q = l - ((l - p0) · n) n``, the origin is
      ``o = q + ((p - q) · x) x``. So the origin lies in the plane (the plane datum), on
      the projected line (the line datum), and level with the point along x (the point
      datum). For the plane ``z = 0``, the line ``y = 5`` along x and the point
      ``(7, 0, 0)`` it is ``(7, 5, 0)``.

    The result ``T = [[x y z o], [0 0 0 1]]`` (the axes as columns) maps coordinates in
    the new frame to coordinates in the frame of the inputs: ``p_in = R p_new + o``. It
    is a proper rigid transform (``R^T R = I``, ``det R = +1``).

    Parameters
    ----------
    plane : Plane
        The primary datum (its normal becomes z).
    line : Line
        The secondary datum (its projected direction becomes x).
    point : array_like, shape (M, 3) or (3,)
        The tertiary datum (it fixes the origin along the projected line), mm.

    Returns
    -------
    ndarray, shape (M, 4, 4)
        The homogeneous transforms.

    Raises
    ------
    DegenerateGeometryError
        If a line is perpendicular to its plane (``|d - (d · n) n| <= RTOL``), so its
        projection has no direction.

    Examples
    --------
    >>> T = frame_from_plane_line_point(
    ...     Plane([0, 0, 1], [0, 0, 1]), Line([0, 0, 0], [0, 1, 1]), [5, 6, 7])
    >>> T[0]
    array([[ 0., -1.,  0.,  0.],
           [ 1.,  0.,  0.,  6.],
           [ 0.,  0.,  1.,  1.],
           [ 0.,  0.,  0.,  1.]])
    """
    pp = check_points(point, "point")
    m = batch_size(plane=plane.point, line=line.point, point=pp)
    z = np.broadcast_to(plane.normal, (m, 3))
    d = line.direction
    xd = d - _dot(d, z)[:, None] * z
    xn = _norm(xd)
    degenerate(
        xn <= RTOL,
        "the line is perpendicular to the plane",
        "a line not perpendicular to the plane",
        "line",
    )
    x = xd / xn[:, None]
    y = _cross(z, x)
    q = project_point_plane(line.point, plane)  # the line's point, in the plane
    o = q + _dot(pp - q, x)[:, None] * x  # on the projected line, level with the point
    T = np.zeros((m, 4, 4))
    T[:, :3, 0] = x
    T[:, :3, 1] = y
    T[:, :3, 2] = z
    T[:, :3, 3] = o
    T[:, 3, 3] = 1.0
    return T


def normal_plane_basis(direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """Two orthonormal columns spanning the plane normal to ``direction``, shape (3, 2).

    The first column is the unit vector of the coordinate axis least aligned with
    ``direction``, made normal to it; the second completes a right-handed set
    ``(e1, e2, d)``.

    Examples
    --------
    >>> normal_plane_basis(np.array([0.0, 0.0, 1.0])).T
    array([[1., 0., 0.],
           [0., 1., 0.]])
    """
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    e = np.zeros(3)
    e[int(np.argmin(np.abs(d)))] = 1.0
    e1 = e - d * (e @ d)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    return np.column_stack([e1, e2])
