"""A site's calibrated model on disk: the bridge, the logger's gains and the detectors' frame.

Contract
--------
* :func:`save_site_model` writes a :class:`~bwim.site.SiteModel` as TOML: the bridge as
  :func:`~bwim.scenario.save_bridge` writes it (exact parameters), and a ``[site_model]``
  table: ``channels`` and their ``gains`` (logger units per unit strain), ``origin`` and
  ``lateral`` (m), ``track_width`` (m), ``tolerance``, ``accepted`` and ``reason``,
  ``weighing_scale``, ``model_error`` and ``truck_weight`` (N), ``provenance`` (what it
  was made from: :attr:`~bwim.site.SiteModel.provenance`), the self-check's ``runs``
  (``index`` from 1, ``explained``, ``gvw_error``, ``reason``) and a ``digest`` of all
  that and the bridge.  Floats are written with :func:`repr`: a saved model reads back bit
  for bit.
* An accepted model is loaded only when its self-check accepts it and its values are
  those the self-check judged (the digest): a model edited by hand is refused.
* :func:`load_site_model` reads it back (``fit`` is None: the fit's details stay with the
  run that made it).  :func:`load_model` reads either such a file (a ``SiteModel``) or any
  bridge or scenario file (a :class:`~bwim.fe.bridge.Bridge`), for ``--bridge``.
"""

from __future__ import annotations

import hashlib
import math
import os
from typing import Any

from bwim.errors import InputError
from bwim.fe.bridge import Bridge
from bwim.io.atomic import atomic_open
from bwim.io.toml_writer import to_toml
from bwim.scenario.bridgefile import bridge_spec
from bwim.scenario.build import build_bridge
from bwim.scenario.parse import read_toml, scenario_from_dict, scenario_to_dict
from bwim.scenario.specs import Scenario
from bwim.site.model import ModelRun, SiteModel

__all__ = ["load_model", "load_site_model", "save_site_model"]

_KEYS = ("channels", "gains", "origin", "lateral", "track_width", "tolerance", "accepted",
         "reason", "weighing_scale", "model_error", "truck_weight", "provenance", "runs",
         "digest")


def _table(model: SiteModel) -> dict[str, Any]:
    """The ``[site_model]`` table of ``model``, without its digest."""
    return {
        "channels": list(model.gains), "gains": [float(g) for g in model.gains.values()],
        "origin": float(model.origin), "lateral": float(model.lateral),
        "track_width": None if model.track_width is None else float(model.track_width),
        "tolerance": float(model.tolerance), "accepted": bool(model.accepted),
        "reason": model.reason, "weighing_scale": float(model.weighing_scale),
        "model_error": None if model.model_error is None else float(model.model_error),
        "truck_weight": None if model.truck_weight is None else float(model.truck_weight),
        "provenance": list(model.provenance),
        "runs": [{"index": r.index + 1, "explained": float(r.explained),
                  "gvw_error": float(r.gvw_error), "reason": r.reason} for r in model.runs],
    }


def _digest(model: SiteModel) -> str:
    """A digest of everything the model weighs with and its self-check's verdict: the
    bridge's exact parameters and the ``[site_model]`` values (the title aside)."""
    doc = scenario_to_dict(Scenario(bridge=bridge_spec(model.bridge)))
    doc["site_model"] = _table(model)
    return "sha256:" + hashlib.sha256(to_toml(doc).encode("utf-8")).hexdigest()[:32]


def save_site_model(model: SiteModel, path: str | os.PathLike, *, title: str = "") -> None:
    """Write ``model`` (module contract), atomically."""
    doc = scenario_to_dict(Scenario(bridge=bridge_spec(model.bridge), title=title))
    doc["site_model"] = {**_table(model), "digest": _digest(model)}
    header = ("bwim site model: the bridge calibrated from logger files, the logger's gains "
              "and the axle detectors' frame.\nWeigh with: bwim weigh SITE.toml traffic/ "
              "--calibration-records calibration/ --bridge THIS.toml")
    with atomic_open(path) as f:
        f.write(to_toml(doc, header=header))


def load_site_model(path: str | os.PathLike) -> SiteModel:
    """The :class:`~bwim.site.SiteModel` of a file :func:`save_site_model` wrote."""
    model = load_model(path)
    if not isinstance(model, SiteModel):
        raise InputError(f"{path}: no [site_model] table: not a site model file")
    return model


def load_model(path: str | os.PathLike) -> SiteModel | Bridge:
    """A site model file's :class:`~bwim.site.SiteModel`, or any scenario's bridge."""
    doc = dict(read_toml(path))
    table = doc.pop("site_model", None)
    bridge = build_bridge(scenario_from_dict(doc, source=path))
    if table is None:
        return bridge
    src = f"{path}: [site_model]"
    if not isinstance(table, dict) or set(table) - set(_KEYS):
        raise InputError(f"{src}: allowed keys are {', '.join(_KEYS)}")
    try:
        channels = [str(c) for c in table["channels"]]
        gains = [_number(g, "a gain", src, 0.0) for g in table["gains"]]
        if len(channels) != len(gains):
            raise InputError(f"{src}: one positive gain per channel is needed")
        if not channels or len(set(channels)) != len(channels):
            raise InputError(f"{src}: channels must name each gauge once, got {channels}")
        runs = tuple(ModelRun(index=_at_least_one(r["index"], src) - 1,
                              explained=float(r["explained"]),
                              gvw_error=float(r["gvw_error"]), reason=str(r.get("reason", "")))
                     for r in table.get("runs", ()))
        track = table.get("track_width")
        error = table.get("model_error")
        truck = table.get("truck_weight")
        model = SiteModel(
            bridge=bridge, gains=dict(zip(channels, gains, strict=True)),
            origin=_number(table["origin"], "origin", src),
            lateral=_number(table["lateral"], "lateral", src),
            track_width=None if track is None else _number(track, "track_width", src, 0.0),
            tolerance=_number(table["tolerance"], "tolerance", src, 0.0, 1.0),
            accepted=_boolean(table["accepted"], "accepted", src),
            reason=str(table.get("reason", "")),
            weighing_scale=_number(table.get("weighing_scale", 1.0), "weighing_scale", src,
                                   0.0),
            model_error=None if error is None else _not_negative(error, "model_error", src),
            truck_weight=None if truck is None else _number(truck, "truck_weight", src, 0.0),
            provenance=tuple(str(x) for x in table.get("provenance", ())), runs=runs)
    except InputError:
        raise
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{src}: missing or mistyped value ({exc})") from None
    if model.accepted:  # what the self-check says, not the flag alone
        bad = next((r for r in model.runs if r.reason or not abs(r.gvw_error)
                    <= model.tolerance), None)
        if model.reason or not model.runs or bad is not None:
            why = (model.reason or "no run checked" if bad is None else
                   f"run {bad.index + 1}: {bad.reason or f'GVW error {bad.gvw_error:+.3f}'}")
            raise InputError(f"{src}: accepted = true, but its self-check does not accept "
                             f"it ({why}, tolerance {model.tolerance:g})")
        # ... and the values it judged: a bridge or gain edited since weighs unchecked
        # (review of stop 37: E_x doubled by hand, every weight 1.85 times too high)
        if table.get("digest") != _digest(model):
            raise InputError(f"{path}: its values are not those its self-check judged (no "
                             "digest, or another): calibrate it again (bwim calibrate) "
                             "rather than edit it")
    return model


def _number(v: Any, name: str, src: str, above: float | None = None,
            below: float | None = None) -> float:
    """A finite number of the table (strictly above ``above``, below ``below``)."""
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) \
            or (above is not None and not v > above) or (below is not None and not v < below):
        bounds = "".join([f", above {above:g}" if above is not None else "",
                          f", below {below:g}" if below is not None else ""])
        raise InputError(f"{src}: {name} must be a finite number{bounds}, got {v!r}")
    return float(v)


def _not_negative(v: Any, name: str, src: str) -> float:
    x = _number(v, name, src)
    if x < 0:
        raise InputError(f"{src}: {name} must not be negative, got {v!r}")
    return x


def _boolean(v: Any, name: str, src: str) -> bool:
    if not isinstance(v, bool):
        raise InputError(f"{src}: {name} must be true or false, got {v!r}")
    return v


def _at_least_one(v: Any, src: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise InputError(f"{src}: a run's index counts from 1, got {v!r}")
    return v
