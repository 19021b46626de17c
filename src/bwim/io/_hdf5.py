"""Shared HDF5 layout of bwim's own files: format tag, sensors, passages, channels.

Contract
--------
* Every bwim HDF5 file carries the root attributes ``bwim_format`` (``"record"``,
  ``"records"``, ``"identification"``, ``"static_weights"``, ``"influence_line"``) and
  ``bwim_format_version`` (an integer, :data:`VERSION`).  :func:`h5_reader` refuses a
  missing file, a file that is not HDF5, a file of another format and a newer version,
  each with an :class:`~bwim.errors.InputError` naming the file (a path that is not a regular
  file, such as a FIFO or a device, is refused before it is opened); a missing dataset inside
  is reported as a damaged file, and so is any content of the wrong type, shape or
  encoding (the reader never lets a TypeError or ValueError escape).
* :func:`h5_writer` writes atomically (:func:`bwim.io.atomic.atomic_output`).
* Readers check each dataset's declared shape × item size against
  :func:`bwim.limits.check_memory` before reading it.
* Arrays are stored as float64 / int64 / bool datasets and scalars as attributes, so
  every number reads back bit for bit; strings are UTF-8.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import h5py
import numpy as np

from bwim.errors import InputError
from bwim.io._csv import open_regular
from bwim.io.atomic import atomic_output
from bwim.limits import check_memory
from bwim.records import Passage
from bwim.sensors import Sensor
from bwim.wim.influence_line import Channel

__all__ = ["VERSION", "h5_reader", "h5_writer"]

VERSION = 1  #: file format version written; readers accept this and older
_STR = h5py.string_dtype(encoding="utf-8")


@contextlib.contextmanager
def h5_writer(path: str | os.PathLike, fmt: str) -> Iterator[h5py.File]:
    """An HDF5 file opened for writing, tagged ``fmt``, that appears only when complete."""
    with atomic_output(path) as tmp, h5py.File(tmp, "w") as f:
        f.attrs["bwim_format"] = fmt
        f.attrs["bwim_format_version"] = VERSION
        yield f


@contextlib.contextmanager
def h5_reader(path: str | os.PathLike, *fmts: str) -> Iterator[h5py.File]:
    """An HDF5 file of one of the formats ``fmts``, opened for reading."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file")
    if p.is_dir():
        raise InputError(f"{p}: is a folder, not a file")
    with open_regular(p):                 # a FIFO or a device: refused, never read
        pass
    try:
        f = h5py.File(p, "r")
    except (OSError, ValueError, RuntimeError, KeyError):
        raise InputError(f"{p}: not an HDF5 file (or it cannot be read)") from None
    with f:
        try:
            fmt = f.attrs.get("bwim_format")
            raw_version = f.attrs.get("bwim_format_version", 0)
        except (OSError, ValueError, TypeError, RuntimeError, KeyError):
            raise InputError(f"{p}: damaged HDF5 attributes") from None
        if isinstance(fmt, bytes):
            fmt = fmt.decode("utf-8", "replace")
        if fmt is None:
            raise InputError(f"{p}: not a bwim file (no bwim_format attribute)")
        if not isinstance(fmt, str) or fmt not in fmts:
            shown = fmt if isinstance(fmt, str) else "(not a name)"
            raise InputError(f"{p}: holds a bwim {shown[:40]}, not a {' or '.join(fmts)}")
        try:
            version = int(raw_version)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"{p}: damaged bwim {fmt} file (bad format version)") from None
        if version > VERSION:
            raise InputError(f"{p}: format version {version} is newer than this bwim reads "
                             f"({VERSION}); update bwim")
        try:
            yield f
        except InputError as exc:
            raise InputError(f"{p}: {exc}") from None
        except KeyError as exc:
            raise InputError(f"{p}: damaged bwim {fmt} file: {exc.args[0] if exc.args else exc}"
                             ) from None
        except (ValueError, TypeError, AttributeError, IndexError, OSError,
                RuntimeError) as exc:  # content of the wrong type, shape or encoding
            raise InputError(f"{p}: damaged bwim {fmt} file ({type(exc).__name__})") from None


def need(group: h5py.Group, name: str):
    """``group[name]`` or a KeyError naming the missing object."""
    if name not in group:
        raise KeyError(f"{group.name.rstrip('/')}/{name} is missing")
    return group[name]


def attr(group: h5py.Group, name: str):
    if name not in group.attrs:
        raise KeyError(f"attribute {name!r} of {group.name} is missing")
    return group.attrs[name]


def _sized(group: h5py.Group, name: str):
    """``group[name]`` as a dataset whose declared size fits the memory limit (checked
    before a byte is read: a small file may declare a huge dataset)."""
    ds = need(group, name)
    if not isinstance(ds, h5py.Dataset):
        raise KeyError(f"{group.name.rstrip('/')}/{name} is not a dataset")
    n = float(np.prod([float(d) for d in ds.shape])) if ds.shape else 1.0
    item = ds.dtype.itemsize if ds.dtype.kind not in "OSU" else 256
    check_memory(n * item, f"the dataset {ds.name} of shape {ds.shape}")
    return ds


def array(group: h5py.Group, name: str) -> np.ndarray:
    return np.asarray(_sized(group, name)[()])


def strings(group: h5py.Group, name: str) -> list[str]:
    return [str(s) for s in _sized(group, name).asstr()[()]]


def put_strings(group: h5py.Group, name: str, values: Sequence[str]) -> None:
    group.create_dataset(name, data=np.array(list(values), dtype=object), dtype=_STR)


def put_sensors(group: h5py.Group, sensors: Sequence[Sensor]) -> None:
    g = group.create_group("sensors")
    g.create_dataset("x", data=np.array([np.nan if s.x is None else s.x for s in sensors],
                                        dtype=float))
    g.create_dataset("y", data=np.array([np.nan if s.y is None else s.y for s in sensors],
                                        dtype=float))
    put_strings(g, "kind", [s.kind.value for s in sensors])
    put_strings(g, "name", [s.name for s in sensors])


def get_sensors(group: h5py.Group) -> tuple[Sensor, ...]:
    g = need(group, "sensors")
    x, y = array(g, "x"), array(g, "y")
    kinds, names = strings(g, "kind"), strings(g, "name")
    # an unknown position (None) is stored as NaN
    return tuple(Sensor(x=None if np.isnan(a) else float(a),
                        y=None if np.isnan(b) else float(b), kind=k, name=n)
                 for a, b, k, n in zip(x, y, kinds, names, strict=True))


def put_passage(group: h5py.Group, passage: Passage) -> None:
    group.attrs["speed"] = passage.speed
    group.attrs["lane"] = passage.lane
    group.attrs["delay"] = passage.delay
    if passage.track_width is not None:
        group.attrs["track_width"] = passage.track_width
    group.create_dataset("axle_spacings", data=passage.axle_spacings)


def get_passage(group: h5py.Group) -> Passage:
    tw = group.attrs.get("track_width")
    return Passage(speed=float(attr(group, "speed")), lane=float(attr(group, "lane")),
                   delay=float(attr(group, "delay")), axle_spacings=array(group, "axle_spacings"),
                   track_width=None if tw is None else float(tw))


def put_list(group: h5py.Group, name: str, items: Sequence, put) -> None:
    """Items as sub-groups ``name/0``, ``name/1``, … written by ``put(subgroup, item)``."""
    g = group.create_group(name)
    g.attrs["count"] = len(items)
    for k, item in enumerate(items):
        put(g.create_group(str(k)), item)


def get_list(group: h5py.Group, name: str, get) -> tuple:
    g = need(group, name)
    return tuple(get(need(g, str(k))) for k in range(int(attr(g, "count"))))


def put_channel(group: h5py.Group, channel: Channel) -> None:
    group.attrs["name"] = channel.name
    put_sensors(group, channel.sensors)


def get_channel(group: h5py.Group) -> Channel:
    return Channel(name=str(attr(group, "name")), sensors=get_sensors(group))
