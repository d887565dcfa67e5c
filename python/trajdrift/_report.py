"""Typed views of trajdrift's results. Each view wraps one object of the JSON the command line writes
(``trajdrift eval --json``, ``trajdrift ape --json``): the common fields are typed attributes, every
other field of the JSON is an attribute too, and ``to_dict()`` gives the JSON object itself."""

from __future__ import annotations

import copy
import json
from typing import Any, Dict, Iterator, List, Mapping, Optional

import numpy as np

__all__ = [
    "Report",
    "EstimateReport",
    "TimeOffset",
    "DriftError",
    "DriftErrors",
    "MetricResult",
    "STATISTICS",
]

#: evo's statistics, in evo's order.
STATISTICS = ("rmse", "mean", "median", "std", "min", "max", "sse")


class _View:
    """One object of the JSON report, with its fields as attributes."""

    __slots__ = ("_d",)

    def __init__(self, d: Dict[str, Any]) -> None:
        self._d = d

    def __getattr__(self, name: str) -> Any:
        # Only the JSON's fields: `_d` itself (not yet set while copy or pickle rebuilds the view) and
        # the special names those protocols look up are not fields.
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._d[name]
        except KeyError:
            raise AttributeError(
                f"{type(self).__name__} has no field {name!r}; fields: {', '.join(self._d)}"
            ) from None

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self._d))

    def to_dict(self) -> Dict[str, Any]:
        """This object as the JSON report writes it (a deep copy)."""
        return copy.deepcopy(self._d)

    def __reduce__(self) -> Any:
        # Copied and pickled (returned from a process pool) as the JSON object it wraps.
        return (type(self), (self._d,))

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other._d == self._d  # type: ignore[attr-defined]

    __hash__ = None  # type: ignore[assignment]


class TimeOffset(_View):
    """The clock offset of an estimate: ``t_est + offset_s`` is the reference's clock."""

    @property
    def offset_s(self) -> float:
        """The offset, seconds (the clock model's value at ``t_mid`` for a linear model)."""
        return self._d["offset_s"]

    @property
    def sigma_s(self) -> Optional[float]:
        """Standard error of ``offset_s``, seconds (``None`` when given or weak)."""
        return self._d.get("sigma_s")

    @property
    def model(self) -> Optional[str]:
        """The clock model applied: ``constant``, ``linear`` (a drift) or ``piecewise`` (steps)."""
        return self._d.get("model")

    @property
    def method(self) -> str:
        """The method whose answer is reported (``speed``, ``signed-curvature``, ``curvature``, or
        ``given``)."""
        return self._d["method"]

    @property
    def status(self) -> str:
        """``ok``, ``weak`` (nothing applied, a warning says why) or ``given``."""
        return self._d["status"]

    @property
    def applied_s(self) -> float:
        """The offset applied before the metrics, seconds (0 when weak)."""
        return self._d["applied_s"]

    @property
    def drift_ppm(self) -> Optional[float]:
        """The clock drift applied (linear model only), ppm."""
        return self._d.get("drift_ppm")

    def __repr__(self) -> str:
        s = self.sigma_s
        sigma = f" ± {s:.4f}" if s is not None else ""
        return (
            f"<TimeOffset {self.offset_s:+.4f}{sigma} s, {self.method}, {self.model or '-'}, "
            f"{self.status}>"
        )


class DriftError(_View):
    """The Drift Error at one window size: statistics over windows of ``window_m`` metres of the
    reference's path (fractions: 0.02 is 2 %)."""

    @property
    def window_m(self) -> float:
        return self._d["window_m"]

    @property
    def rmse(self) -> Optional[float]:
        return self._d["rmse"]

    @property
    def mean(self) -> Optional[float]:
        return self._d["mean"]

    @property
    def median(self) -> Optional[float]:
        return self._d["median"]

    @property
    def std(self) -> Optional[float]:
        return self._d["std"]

    @property
    def windows(self) -> int:
        """Windows evaluated."""
        return self._d["windows"]

    @property
    def values(self) -> np.ndarray:
        """The Drift Error of each window."""
        return np.array([w["de"] for w in self._d["per_window"]], dtype=np.float64)

    def __repr__(self) -> str:
        r = self.rmse
        rmse = f"{100 * r:.2f} %" if r is not None else "-"
        return f"<DriftError {self.window_m:g} m: rmse {rmse} over {self.windows} windows>"


class DriftErrors(Mapping[float, DriftError]):
    """An estimate's Drift Error by window size in metres: ``drift_error[5]``."""

    def __init__(self, items: List[Dict[str, Any]]) -> None:
        self._items = {float(d["window_m"]): DriftError(d) for d in items}

    def __getitem__(self, window_m: float) -> DriftError:
        try:
            return self._items[float(window_m)]
        except (KeyError, TypeError, ValueError):
            raise KeyError(
                f"no Drift Error at {window_m} m; windows: {', '.join(f'{w:g}' for w in self._items)}"
            ) from None

    def __iter__(self) -> Iterator[float]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return repr(list(self._items.values()))


class EstimateReport(_View):
    """One estimate's results."""

    @property
    def name(self) -> str:
        return self._d["name"]

    @property
    def time_offset(self) -> TimeOffset:
        return TimeOffset(self._d["time_offset"])

    @property
    def drift_error(self) -> DriftErrors:
        """The Drift Error by window size in metres: ``drift_error[5].rmse``."""
        return DriftErrors(self._d["drift_error"])

    @property
    def standard_metrics(self) -> Optional[Dict[str, Any]]:
        """evo's APE/RPE (and KITTI drift) on the time-aligned estimate, as the JSON report holds
        them."""
        return self._d.get("standard_metrics")

    def __repr__(self) -> str:
        return f"<EstimateReport {self.name!r}: {self.time_offset!r}, {self.drift_error!r}>"


class Report(_View):
    """The report of an evaluation: ``to_dict()`` is the command line's JSON report
    (``trajdrift eval --json``)."""

    @property
    def estimates(self) -> Dict[str, EstimateReport]:
        """Each estimate's results by name, in the order given."""
        return {e["name"]: EstimateReport(e) for e in self._d["estimates"]}

    @property
    def warnings(self) -> List[Dict[str, str]]:
        """What the user must see beside the numbers (``code``, ``message``); the command line exits
        with 3 when there is one."""
        return self._d["warnings"]

    @property
    def parameters(self) -> Dict[str, Any]:
        """Every parameter that shaped the numbers."""
        return self._d["parameters"]

    def to_json(self, indent: Optional[int] = 2) -> str:
        """The JSON report as text."""
        return json.dumps(self._d, indent=indent)

    def __repr__(self) -> str:
        names = ", ".join(self.estimates)
        return f"<Report: {len(self._d['estimates'])} estimates ({names}), {len(self.warnings)} warnings>"


class MetricResult(_View):
    """An APE or RPE result, as evo's ``Result``: ``stats`` with evo's keys, ``np_arrays`` with evo's
    per-value arrays; ``to_dict()`` is ``trajdrift ape --json``'s object."""

    __slots__ = ("_arrays",)

    def __init__(self, d: Dict[str, Any], arrays: Dict[str, Any]) -> None:
        super().__init__(d)
        self._arrays = arrays

    def __reduce__(self) -> Any:
        return (type(self), (self._d, self._arrays))

    @property
    def stats(self) -> Dict[str, float]:
        """evo's statistics: rmse, mean, median, std (population), min, max, sse."""
        return {k: self._d["stats"][k] for k in STATISTICS}

    @property
    def np_arrays(self) -> Dict[str, np.ndarray]:
        """evo's arrays: ``error_array`` (one value per pair) and, for stamped trajectories,
        ``timestamps``, ``seconds_from_start``, ``distances_from_start`` (the reference's path length),
        ``distances`` (the estimate's)."""
        out = {"error_array": self._arrays["error_array"]}
        if self._arrays["timestamps"] is not None:
            for k in ("seconds_from_start", "timestamps", "distances_from_start", "distances"):
                out[k] = self._arrays[k]
        return out

    @property
    def error_array(self) -> np.ndarray:
        """The error of each pose pair."""
        return self._arrays["error_array"]

    @property
    def pairs(self) -> Optional[np.ndarray]:
        """RPE: the (i, j) indices of the associated poses each value compares, shape (n, 2)."""
        return self._arrays["pairs"]

    @property
    def rmse(self) -> float:
        return self._d["stats"]["rmse"]

    @property
    def mean(self) -> float:
        return self._d["stats"]["mean"]

    @property
    def median(self) -> float:
        return self._d["stats"]["median"]

    @property
    def std(self) -> float:
        return self._d["stats"]["std"]

    @property
    def min(self) -> float:
        return self._d["stats"]["min"]

    @property
    def max(self) -> float:
        return self._d["stats"]["max"]

    @property
    def sse(self) -> float:
        return self._d["stats"]["sse"]

    @property
    def alignment(self) -> Dict[str, Any]:
        """The alignment applied: method, rotation (3×3, row-major), translation_m, scale,
        poses_used."""
        return self._d["alignment"]

    def __repr__(self) -> str:
        unit = self._d["unit"]
        return (
            f"<{self._d['metric'].upper()} {self._d['relation']}: rmse {self.rmse:.6f} {unit} over "
            f"{self._d['pairs']} pairs>"
        )
