"""Results on disk (HDF5): force identifications, static weights, influence lines.

Contract
--------
* :func:`write_identification` / :func:`read_identification` round-trip a
  :class:`~bwim.ForceIdentification` exactly, its L-curve included when it has one.
* :func:`write_static_weights` / :func:`read_static_weights` round-trip a
  :class:`~bwim.StaticWeights` (Moses) exactly, channels and axle groups included.
* :func:`write_influence_line` / :func:`read_influence_line` round-trip an
  :class:`~bwim.InfluenceLine`, so that a line calibrated in one run weighs in the next.
* Writers are atomic (:mod:`bwim.io.atomic`); readers refuse a file of another bwim
  format with a message naming both (``"out.h5: holds a bwim record, not a
  identification"``).

Layouts (datasets; ``@`` marks attributes)::

    identification: time wheel_forces axle_forces axle_weights gvw fitted axle_windows
                    @lam @lam_scaled @unknowns @order  passages/…
                    lcurve/ lam lam_scaled residual_norm seminorm curvature
                            @corner @corner_scaled                     (if present)
    static_weights: axle_weights time measured fitted  @residual @condition
                    groups_axles groups_sizes  channels/…  passage/
    influence_line: x ordinates  @lane [@track_width] @source [@residual]  channels/…
"""

from __future__ import annotations

import os

import h5py
import numpy as np

from bwim.errors import InputError
from bwim.io import _hdf5 as h5
from bwim.mfi.identify import ForceIdentification
from bwim.mfi.lcurve import LCurve
from bwim.mfi.statespace import ForceUnknowns, Order
from bwim.wim.influence_line import InfluenceLine
from bwim.wim.moses import StaticWeights

__all__ = [
    "read_identification",
    "read_influence_line",
    "read_static_weights",
    "write_identification",
    "write_influence_line",
    "write_static_weights",
]

_IDENT_ARRAYS = ("time", "wheel_forces", "axle_forces", "axle_weights", "gvw", "fitted",
                 "axle_windows")
_LCURVE_ARRAYS = ("lam", "lam_scaled", "residual_norm", "seminorm", "curvature")


def _check(obj, cls) -> None:
    if not isinstance(obj, cls):
        raise InputError(f"expected a bwim.{cls.__name__}, got {type(obj).__name__}")


def write_identification(ident: ForceIdentification, path: str | os.PathLike) -> None:
    """Write a force identification to HDF5 (see the module docstring)."""
    _check(ident, ForceIdentification)
    with h5.h5_writer(path, "identification") as f:
        for name in _IDENT_ARRAYS:
            f.create_dataset(name, data=np.asarray(getattr(ident, name), dtype=float))
        f.attrs["lam"] = float(ident.lam)
        f.attrs["lam_scaled"] = float(ident.lam_scaled)
        f.attrs["unknowns"] = ForceUnknowns(ident.unknowns).value
        f.attrs["order"] = Order(ident.order).value
        f.attrs["residual"] = float(ident.residual)
        h5.put_list(f, "passages", ident.passages, h5.put_passage)
        if ident.lcurve is not None:
            g = f.create_group("lcurve")
            for name in _LCURVE_ARRAYS:
                g.create_dataset(name, data=np.asarray(getattr(ident.lcurve, name), dtype=float))
            g.attrs["corner"] = float(ident.lcurve.corner)
            g.attrs["corner_scaled"] = float(ident.lcurve.corner_scaled)


def read_identification(path: str | os.PathLike) -> ForceIdentification:
    """Read a force identification written by :func:`write_identification`."""
    with h5.h5_reader(path, "identification") as f:
        curve = None
        if "lcurve" in f:
            g = f["lcurve"]
            curve = LCurve(**{n: h5.array(g, n) for n in _LCURVE_ARRAYS},
                           corner=float(h5.attr(g, "corner")),
                           corner_scaled=float(h5.attr(g, "corner_scaled")))
        return ForceIdentification(
            **{n: h5.array(f, n) for n in _IDENT_ARRAYS},
            lam=float(h5.attr(f, "lam")), lam_scaled=float(h5.attr(f, "lam_scaled")),
            lcurve=curve, passages=h5.get_list(f, "passages", h5.get_passage),
            unknowns=ForceUnknowns(str(h5.attr(f, "unknowns"))),
            order=Order(str(h5.attr(f, "order"))),
            residual=float(f.attrs.get("residual", np.nan)),
        )


def _put_groups(f: h5py.Group, groups) -> None:
    f.create_dataset("groups_axles", data=np.array([i for g in groups for i in g], dtype=int))
    f.create_dataset("groups_sizes", data=np.array([len(g) for g in groups], dtype=int))


def _get_groups(f: h5py.Group) -> tuple[tuple[int, ...], ...]:
    axles = h5.array(f, "groups_axles").astype(int)
    sizes = h5.array(f, "groups_sizes").astype(int)
    if sizes.sum() != axles.size:
        raise KeyError("axle groups do not add up")
    ends = np.cumsum(sizes)
    return tuple(tuple(int(i) for i in axles[e - s:e]) for s, e in zip(sizes, ends, strict=True))


def write_static_weights(weights: StaticWeights, path: str | os.PathLike) -> None:
    """Write Moses' static weights to HDF5 (see the module docstring)."""
    _check(weights, StaticWeights)
    with h5.h5_writer(path, "static_weights") as f:
        for name in ("axle_weights", "time", "measured", "fitted"):
            f.create_dataset(name, data=np.asarray(getattr(weights, name), dtype=float))
        f.attrs["residual"] = float(weights.residual)
        f.attrs["condition"] = float(weights.condition)
        _put_groups(f, weights.groups)
        h5.put_list(f, "channels", weights.channels, h5.put_channel)
        h5.put_passage(f.create_group("passage"), weights.passage)


def read_static_weights(path: str | os.PathLike) -> StaticWeights:
    """Read static weights written by :func:`write_static_weights`."""
    with h5.h5_reader(path, "static_weights") as f:
        return StaticWeights(
            axle_weights=h5.array(f, "axle_weights"), time=h5.array(f, "time"),
            measured=h5.array(f, "measured"), fitted=h5.array(f, "fitted"),
            channels=h5.get_list(f, "channels", h5.get_channel),
            passage=h5.get_passage(h5.need(f, "passage")),
            residual=float(h5.attr(f, "residual")), condition=float(h5.attr(f, "condition")),
            groups=_get_groups(f),
        )


def write_influence_line(line: InfluenceLine, path: str | os.PathLike) -> None:
    """Write an influence line to HDF5 (see the module docstring)."""
    _check(line, InfluenceLine)
    with h5.h5_writer(path, "influence_line") as f:
        f.create_dataset("x", data=line.x)
        f.create_dataset("ordinates", data=line.ordinates)
        f.attrs["lane"] = float(line.lane)
        f.attrs["source"] = line.source
        if line.track_width is not None:
            f.attrs["track_width"] = float(line.track_width)
        if line.residual is not None:
            f.attrs["residual"] = float(line.residual)
        h5.put_list(f, "channels", line.channels, h5.put_channel)


def read_influence_line(path: str | os.PathLike) -> InfluenceLine:
    """Read an influence line written by :func:`write_influence_line`."""
    with h5.h5_reader(path, "influence_line") as f:
        tw = f.attrs.get("track_width")
        res = f.attrs.get("residual")
        return InfluenceLine(
            x=h5.array(f, "x"), ordinates=h5.array(f, "ordinates"),
            channels=h5.get_list(f, "channels", h5.get_channel),
            lane=float(h5.attr(f, "lane")), source=str(h5.attr(f, "source")),
            track_width=None if tw is None else float(tw),
            residual=None if res is None else float(res),
        )
