"""appell: fit dry friction on a Painleve-Appell rig from Python.

The same library as the ``appell`` command, called in-process: a fit here gives the numbers of
``appell fit`` to the last digit, and ``FitResult.to_dict()`` is its ``--json``. Keyword
arguments carry the command's flag names (``--fit-rod-length`` is ``fit_rod_length=True``,
``--with`` is ``with_``) and defaults. Bad input raises ``ValueError`` with the command's
message; a run that cannot finish raises ``RuntimeError``. Long calls release the GIL, so
threads fit in parallel.

    >>> import appell
    >>> result = appell.fit("data/example_recording.mcap", "configs/rig_example.toml")
    >>> result.answer
    'mu_kinetic = 0.119922 +- 0.000049 (95 %: 0.119825 to 0.120018), model adequate'
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import warnings
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from . import _appell

__all__ = [
    "Recording",
    "Rig",
    "FitResult",
    "JointResult",
    "Simulation",
    "Plan",
    "Regions",
    "Inspection",
    "read_recording",
    "inspect",
    "fit",
    "fit_joint",
    "fit_many",
    "simulate",
    "plan",
    "synth",
    "regions",
    "READ_OPTIONS",
    "FIT_OPTIONS",
    "NO_UNIT",
]

__version__ = "0.1.0"

PathLike = Union[str, "os.PathLike[str]"]

#: Reading options (``appell convert``/``fit`` flags) and their defaults.
READ_OPTIONS: Mapping[str, Any] = {
    "format": None,
    "slider": None,
    "bob": None,
    "scale": None,
    "fps": None,
    "plane": None,
    "y_down": False,
    "y_up": False,
    "rail_frame": False,
    "rod_length": None,
    "min_likelihood": 0.6,
    "drop_outliers": False,
    "t_start": None,
    "t_end": None,
    "topic": (),
}

#: Fit options (``appell fit`` flags) and their defaults; ``with_`` is ``--with``.
FIT_OPTIONS: Mapping[str, Any] = {
    "latitude": None,
    "altitude": None,
    "robust": None,
    "fit_rod_length": False,
    "mu_static": "auto",
    "no_profile": False,
    "starts": (),
    "noise": (),
    "plain": False,
    "with_": (),
    "friction": None,
}


def _split(options: Mapping[str, Any], where: str, read_ok: bool = True, fit_ok: bool = True):
    """Options by kind, every key filled with its default; a name the call does not take
    (unknown, or a reading option for arrays, a fit option for a reading) is a TypeError."""
    read = dict(READ_OPTIONS)
    fit_opts = dict(FIT_OPTIONS)
    for name, value in options.items():
        key = "with_" if name == "with" else name
        if read_ok and key in read:
            read[key] = value
        elif fit_ok and key in fit_opts:
            fit_opts[key] = value
        else:
            known = sorted(list(READ_OPTIONS) * read_ok + list(FIT_OPTIONS) * fit_ok)
            raise TypeError(
                f"{where}() got an unexpected keyword argument {name!r}; "
                f"it takes {', '.join(known)}"
            )
    return _read_kw(read), _fit_kw(fit_opts)


def _strings(value: Any) -> list:
    if value is None:
        return []
    if isinstance(value, (str, bytes, os.PathLike)) or not isinstance(value, Iterable):
        value = [value]
    return list(value)


def _read_kw(read: dict) -> dict:
    read = dict(read)
    read["topic"] = [str(t) for t in _strings(read["topic"])]
    for key in ("scale", "fps", "rod_length", "t_start", "t_end", "min_likelihood"):
        if read[key] is not None:
            read[key] = float(read[key])
    return read


def _fit_kw(fit_opts: dict) -> dict:
    fit_opts = dict(fit_opts)
    # Noise as the CLI takes it: metres, or pixels with a "px" suffix; repr keeps every digit.
    fit_opts["noise"] = [
        v if isinstance(v, str) else repr(float(v)) for v in _strings(fit_opts["noise"])
    ]
    fit_opts["starts"] = [float(s) for s in _strings(fit_opts["starts"])]
    fit_opts["with"] = [str(n) for n in _strings(fit_opts.pop("with_"))]
    for key in ("latitude", "altitude"):
        if fit_opts[key] is not None:
            fit_opts[key] = float(fit_opts[key])
    return fit_opts


def _path(value: Any, name: str) -> str:
    """A path argument as text: a ``str``, ``bytes`` (decoded as the file system does) or
    ``os.PathLike``; anything else is a TypeError naming the argument."""
    if isinstance(value, (str, bytes, os.PathLike)):
        return os.fsdecode(value)
    raise TypeError(
        f"{name} must be a path (str, bytes or os.PathLike), got {type(value).__name__} {value!r}"
    )


def _is_path(value: Any) -> bool:
    return isinstance(value, (str, bytes, os.PathLike))


def _paths(recording: Any, name: str = "recording") -> list:
    """A recording's files: one path, or a list of them (a Tracker pair)."""
    if _is_path(recording):
        return [_path(recording, name)]
    if not isinstance(recording, Iterable):
        _path(recording, name)  # the TypeError naming the argument
    return [_path(p, f"{name}[{i}]") for i, p in enumerate(recording)]


def _array(value: Any, name: str, columns: Optional[int]) -> np.ndarray:
    """``value`` as a C-contiguous float64 array of shape (n,) (``columns`` None) or
    (n, columns), checked before it is copied: its length against the frames a file may hold,
    its shape, its type. A ValueError or TypeError names the argument and the fix."""
    arr = value if isinstance(value, np.ndarray) else np.asarray(value)
    want = "(n,)" if columns is None else f"(n, {columns})"
    if columns is None and arr.ndim == 2 and arr.shape[1] == 1:
        arr = arr[:, 0]
    if columns is None and arr.ndim != 1:
        raise ValueError(f"{name}: expected shape {want}, one time per frame, got {arr.shape}")
    if columns is not None and not (arr.ndim == 2 and arr.shape[1] == columns):
        turned = f": transpose it ({name}.T)" if arr.ndim == 2 and arr.shape[0] == columns else ""
        raise ValueError(
            f"{name}: expected shape {want}, a row of x, y per frame, got {arr.shape}{turned}"
        )
    _appell.check_frames_py(arr.shape[0])
    if arr.dtype.kind in "iuf":
        return np.ascontiguousarray(arr, dtype=np.float64)
    try:
        if arr.dtype.kind not in "OSU":  # bool, complex, dates: not positions nor times
            raise TypeError
        return np.ascontiguousarray(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(
            f"{name}: expected real numbers (float64, or a dtype numpy converts to it), got "
            f"dtype {arr.dtype}"
        ) from None


class Recording:
    """Frame times and the two marker tracks, in the rail frame (metres, y up).

    ``t`` has shape (n,); ``slider`` and ``bob`` have shape (n, 2), NaN where the marker was
    not seen. ``metadata`` says where it came from (format, marker names, scale, notes).
    Build one from your own arrays with ``Recording(t, slider, bob)``.
    """

    def __init__(self, t, slider, bob, metadata: Optional[dict] = None):
        self.t = t
        self.slider = slider
        self.bob = bob
        self._arrays()
        self.metadata = dict(metadata or {})

    # Arrays are converted and checked where they are set, and again where they cross into
    # the library (``_arrays``): a float32 array, a list or a (2, n) array assigned later is
    # converted or refused, never read by its raw bytes.
    @property
    def t(self) -> np.ndarray:
        """Frame times, seconds, shape (n,)."""
        return self._t

    @t.setter
    def t(self, value) -> None:
        self._t = _array(value, "t", None)

    @property
    def slider(self) -> np.ndarray:
        """The slider's track, metres in the rail frame, shape (n, 2), NaN where not seen."""
        return self._slider

    @slider.setter
    def slider(self, value) -> None:
        self._slider = _array(value, "slider", 2)

    @property
    def bob(self) -> np.ndarray:
        """The bob's track, metres in the rail frame, shape (n, 2), NaN where not seen."""
        return self._bob

    @bob.setter
    def bob(self, value) -> None:
        self._bob = _array(value, "bob", 2)

    def _arrays(self) -> tuple:
        """``t``, ``slider`` and ``bob`` checked again as they cross into the library: their
        shapes, types and one row per frame."""
        t = _array(self._t, "t", None)
        slider = _array(self._slider, "slider", 2)
        bob = _array(self._bob, "bob", 2)
        if not (len(t) == len(slider) == len(bob)):
            raise ValueError(
                f"t, slider and bob must have one row per frame: got {len(t)}, "
                f"{len(slider)} and {len(bob)}"
            )
        return t, slider, bob

    @classmethod
    def _from_rust(cls, d: dict) -> "Recording":
        return cls(
            np.frombuffer(d["t"], dtype=np.float64),
            np.frombuffer(d["slider"], dtype=np.float64).reshape(-1, 2),
            np.frombuffer(d["bob"], dtype=np.float64).reshape(-1, 2),
            d.get("metadata"),
        )

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        seen = (int(np.isfinite(self.slider[:, 0]).sum()), int(np.isfinite(self.bob[:, 0]).sum()))
        span = f"{self.t[-1] - self.t[0]:.4g} s" if len(self.t) else "empty"
        fmt = self.metadata.get("format")
        return (
            f"<Recording {len(self)} frames, {span}, slider seen {seen[0]}, bob seen {seen[1]}"
            + (f", read as {fmt}" if fmt else "")
            + ">"
        )

    def to_pandas(self):
        """A DataFrame with the canonical columns t, slider_x, slider_y, bob_x, bob_y."""
        import pandas as pd

        return pd.DataFrame(
            {
                "t": self.t,
                "slider_x": self.slider[:, 0],
                "slider_y": self.slider[:, 1],
                "bob_x": self.bob[:, 0],
                "bob_y": self.bob[:, 1],
            }
        )


def read_recording(path: Union[PathLike, Sequence[PathLike]], **options) -> Recording:
    """Read a recording as ``appell convert`` does (CSV family, MCAP, DeepLabCut and SLEAP
    HDF5, Tracker, Motive, Qualisys, Kinovea...). A Tracker pair is a list of two files.
    Options: ``READ_OPTIONS`` (``fps=``, ``scale=``, ``rod_length=``, ``rail_frame=``...)."""
    read, _ = _split(options, "read_recording", fit_ok=False)
    d = _appell.read_recording_py(_paths(path, "path"), read)
    _warn_fps([d.get("fps_note")])
    return Recording._from_rust(d)


def _warn_fps(notes: Iterable[Optional[str]]) -> None:
    """Say that ``fps`` was given to files with their own frame times, which were read instead
    (the reader ignores it there): a ``UserWarning`` per file, as a note is printed per file."""
    for note in notes:
        if note:
            warnings.warn(note, UserWarning, stacklevel=3)


class Inspection:
    """What a recording holds before its options are known (``appell inspect``): the format,
    the markers, times and units, which pair looks like the slider and the bob, the options
    still missing, and ready ``fit``/``convert`` commands. ``to_dict()`` is ``--json``."""

    def __init__(self, parts):
        self._json, self._text = parts

    def to_dict(self) -> dict:
        return json.loads(self._json)

    def report(self) -> str:
        return self._text

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(self._text)}</pre>"

    def __repr__(self) -> str:
        return self._text


def inspect(path: Union[PathLike, Sequence[PathLike]], **options) -> Inspection:
    """What a recording file holds and every option still missing to read it as the rig
    (``appell inspect``); options already known (``fps=``, ``slider=``...) are used and carried
    into the suggested commands. A Tracker pair is a list of two files."""
    read, _ = _split(options, "inspect", fit_ok=False)
    return Inspection(_appell.inspect_py(_paths(path, "path"), read))


def _toml_value(key: str, value: Any) -> str:
    if isinstance(value, bool) or value is None:
        raise ValueError(f"Rig: {key} = {value!r}: expected a number or a name")
    if isinstance(value, (int, float, np.floating, np.integer)):
        return repr(float(value))
    if isinstance(value, str):
        return json.dumps(value)
    raise ValueError(f"Rig: {key} = {value!r}: expected a number or a name")


class Rig:
    """A rig as the lab measured it: the ``[rig]`` section of a rig file.

    ``Rig(slider_mass=0.3, bob_mass=0.15, rod_length=0.25, rod_length_sd=0.001)`` takes the
    file's keys (docs/formats.md); ``Rig.from_toml("rig.toml")`` reads a file. The values are
    checked at once (``ValueError`` naming the key). Each is a measurement: the fit takes its
    ``*_sd`` (or the defaults: a ruler's 1 mm, a scale's few percent) as a prior.
    """

    def __init__(self, **keys: Any):
        lines = ["[rig]"] + [f"{k} = {_toml_value(k, v)}" for k, v in keys.items()]
        self.keys = dict(keys)
        self.text = "\n".join(lines) + "\n"
        self.label = "Rig(" + ", ".join(f"{k}={v!r}" for k, v in keys.items()) + ")"
        _appell.check_rig_py(self.text, self.label)

    @classmethod
    def from_toml(cls, path: PathLike) -> "Rig":
        """Read a rig file (or a scene, whose ``[rig]`` is used)."""
        rig = cls.__new__(cls)
        rig.label = _path(path, "path")
        rig.text = _appell.read_toml_py(rig.label)
        rig.keys = None
        _appell.check_rig_py(rig.text, rig.label)
        return rig

    def __repr__(self) -> str:
        return self.label if self.keys is not None else f"Rig.from_toml({self.label!r})"


def _rig(rig: Union[Rig, PathLike]) -> Rig:
    return rig if isinstance(rig, Rig) else Rig.from_toml(_path(rig, "rig"))


class _Result:
    """What fit results share: mu, the JSON, the text report, the figure."""

    #: What the figure shows, for the notebook's image.
    _figure_alt = "the fit's figure"

    def __init__(self, inner):
        self._inner = inner
        self._parsed = None

    @property
    def _dict(self) -> dict:
        # Parsed on first use: a fit in a loop that only keeps the answer never pays for it.
        if self._parsed is None:
            self._parsed = self.to_dict()
        return self._parsed

    @property
    def mu(self) -> Optional[float]:
        """mu_kinetic (None when the fit gave no value)."""
        return (self._dict.get("mu_kinetic") or {}).get("value")

    @property
    def stderr(self) -> Optional[float]:
        """mu_kinetic's standard error."""
        return (self._dict.get("mu_kinetic") or {}).get("stderr")

    @property
    def interval(self):
        """mu_kinetic's 95 % interval (low, high)."""
        return _interval(self._dict.get("mu_kinetic") or {})

    def to_dict(self) -> dict:
        """The command's ``--json`` object."""
        return json.loads(self._inner.json())

    def report(self) -> str:
        """The report the command prints."""
        return self._inner.text()

    @property
    def answer(self) -> str:
        """One line: mu, its interval, and what limits it."""
        return self._inner.answer()

    @property
    def notes(self) -> list:
        """What the command would print on stderr (notes, left-out releases)."""
        return list(self._inner.notes())

    def svg(self) -> str:
        """The figure as SVG text."""
        return self._inner.svg()

    def plot(self, path: PathLike) -> None:
        """Write the figure, SVG or PNG by the extension (never over an input)."""
        self._inner.plot(_path(path, "path"))

    @property
    def parameters(self) -> dict:
        """Every fitted value: name to ``value``, ``stderr``, ``ci95``, ``interval`` (how it
        was computed) and ``unit``."""
        return {}

    def _table_rows(self) -> list:
        return _parameter_rows(self.parameters)

    def _repr_html_(self) -> str:
        rows = "".join(
            "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
            for r in self._table_rows()
        )
        table = (
            "<table><tr><th>parameter</th><th>value</th><th>stderr</th><th>95 %</th>"
            f"<th>unit</th></tr>{rows}</table>"
            if rows
            else ""
        )
        try:
            figure = _svg_img(self.svg(), self._figure_alt)
        except (RuntimeError, ValueError) as e:
            figure = f"<p>(no figure: {html.escape(str(e))})</p>"
        return (
            f"<div><p><b>{html.escape(self.answer)}</b></p>{table}"
            f"<details><summary>report</summary><pre>{html.escape(self.report())}</pre></details>"
            f"{figure}</div>"
        )


def _svg_img(svg: str, alt: str = "the figure") -> str:
    """An SVG figure as an image that shrinks to the notebook's width (an inline <svg> keeps
    its 1000 px and is cut off), with `alt` saying what it shows."""
    data = base64.b64encode(svg.encode()).decode()
    return (
        f"<img alt='{html.escape(alt, quote=True)}' style='max-width:100%;height:auto' "
        f"src='data:image/svg+xml;base64,{data}'/>"
    )


def _interval(entry: Mapping[str, Any]):
    ci = entry.get("ci95") or [None, None]
    return (ci[0], ci[1])


#: How a parameter without a unit (mu, a mass ratio) shows in the tables' unit column.
NO_UNIT = "dimensionless"


def _digits(stderr: Any):
    """How to print a value and its standard error: to two digits of the error, as the
    command's tables do (six significant digits when there is no error)."""
    if isinstance(stderr, (int, float)) and math.isfinite(stderr) and stderr > 0:
        d = max(0, 1 - math.floor(math.log10(stderr)))
        return lambda v: f"{v:.{d}f}"
    return lambda v: f"{v:.6g}"


def _parameter_rows(parameters: Mapping[str, Any]) -> list:
    """Table rows (name, value, stderr, 95 % interval, unit) of fitted values, each to the
    digits its standard error gives."""
    rows = []
    for name, p in parameters.items():
        if not (isinstance(p, dict) and "value" in p):
            continue
        lo, hi = _interval(p)
        se = p.get("stderr")
        fmt = _digits(se)
        unit = p.get("unit")
        rows.append(
            [name, fmt(p["value"]), fmt(se) if se is not None else "",
             f"{fmt(lo)} to {fmt(hi)}" if lo is not None else "",
             unit if unit else NO_UNIT]
        )
    return rows


class FitResult(_Result):
    """One recording's fit. ``mu``, ``interval``, ``stderr``; ``parameters`` (every fitted
    value), ``models`` (the models compared), ``to_dict()`` (``appell fit --json``),
    ``report()`` (its text), ``answer``, ``svg()``/``plot(path)``/``friction_plot(path)``."""

    _figure_alt = "the fit: data and model, residuals and the slides' mu over time"

    @property
    def parts(self) -> dict:
        """Where mu's uncertainty comes from (noise, model, ...)."""
        return (self._dict.get("mu_kinetic") or {}).get("parts") or {}

    @property
    def parameters(self) -> dict:
        """Every fitted parameter: value, stderr, ci95, interval kind, unit."""
        out = {}
        for name in ("mu_kinetic", "mu_static"):
            if isinstance(self._dict.get(name), dict):
                out[name] = self._dict[name]
        out.update(self._dict.get("parameters") or {})
        return out

    @property
    def initial(self) -> dict:
        """The fitted initial state (x, theta, x_dot, theta_dot)."""
        return self._dict.get("initial") or {}

    @property
    def models(self) -> list:
        """The models compared (nuisances, friction laws) with their BIC."""
        return self._dict.get("models") or []

    @property
    def limited_by_model(self) -> Optional[str]:
        """What the model misses (None: the model is adequate)."""
        return self._dict.get("limited_by_model")

    @property
    def warnings(self) -> list:
        return self._dict.get("warnings") or []

    def friction_plot(self, path: PathLike) -> None:
        """Write the friction figure: each slide's |F|/|N| against its speed, with the laws."""
        self._inner.friction_plot(_path(path, "path"))

    def __repr__(self) -> str:
        return f"<FitResult {self.answer}>"


class JointResult(_Result):
    """Releases of one rig fitted together (``appell fit --joint``). ``mu``, ``interval``,
    ``stderr``; ``parameters`` (the values every release shares), ``releases`` (one row per
    release), ``to_dict()`` (``appell fit --joint --json``), ``report()``, ``answer``,
    ``svg()``/``plot(path)``. In Jupyter it shows the answer, the shared values and the
    releases as tables, the report and the figure."""

    _figure_alt = "each release's own mu with its 95 % bar, and the joint value"

    @property
    def failed(self) -> Optional[str]:
        """Why the joint fit gave no value (None: it gave one)."""
        return self._inner.failed()

    @property
    def parameters(self) -> dict:
        """The values every release shares (mu_kinetic first, the friction law's, the rail's
        tilt, the pendulum's): value, stderr, ci95, interval kind, unit."""
        shared = self._dict.get("shared") or {}
        first = [k for k in ("mu_kinetic", "mu_static") if k in shared]
        return {k: shared[k] for k in first + [k for k in shared if k not in first]}

    def _release_rows(self) -> list:
        rows = []
        set_aside = self._dict.get("set_aside") or []
        for r in self.releases + set_aside:
            own = r.get("own_mu") or {}
            z = r.get("z")
            fmt = _digits(own.get("stderr"))
            rows.append([
                r.get("name", ""),
                r.get("frames", ""),
                f"{fmt(own['value'])} +- {fmt(own['stderr'])}" if "stderr" in own else "",
                f"{z:.2f}" if isinstance(z, (int, float)) else "",
                "set aside" if r in set_aside else "yes" if r.get("agrees") else "no",
            ])
        return rows

    def _repr_html_(self) -> str:
        page = super()._repr_html_()
        rows = self._release_rows()
        if not rows:
            return page
        body = "".join(
            "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
            for r in rows
        )
        releases = (
            "<table><tr><th>release</th><th>frames</th><th>own mu +- stderr</th>"
            f"<th>z</th><th>agrees</th></tr>{body}</table>"
        )
        # After the shared table, before the report.
        return page.replace("<details>", releases + "<details>", 1)

    @property
    def releases(self) -> list:
        """One row per release: its name, its own mu, and how it agrees with the others."""
        return self._dict.get("releases") or []

    def __repr__(self) -> str:
        return f"<JointResult {self.answer}>"


def fit(
    recording: Union[PathLike, Sequence[PathLike], Recording],
    rig: Union[Rig, PathLike],
    *,
    plot: Optional[PathLike] = None,
    friction_plot: Optional[PathLike] = None,
    threads: Optional[int] = None,
    **options,
) -> FitResult:
    """Fit mu and the initial state to one recording, as ``appell fit`` does.

    ``recording`` is a file (a Tracker pair: a list of two files) read with ``READ_OPTIONS``,
    or a :class:`Recording` (arrays: rail frame, metres). ``rig`` is a :class:`Rig` or a rig
    file. ``options``: ``FIT_OPTIONS`` and, for files, ``READ_OPTIONS``. ``threads``: None
    (one fit at a time uses every core), or the fit's own pool of that many threads (1 when
    you fit in parallel yourself, by threads or processes, so the fits do not queue for one
    shared pool)."""
    r = _rig(rig)
    if isinstance(recording, Recording):
        read, fit_opts = _split(options, "fit", read_ok=False)
        arrays = tuple(a.tobytes() for a in recording._arrays())
        inner = _appell.fit_py([], arrays, r.text, r.label, read, fit_opts, threads)
    else:
        read, fit_opts = _split(options, "fit")
        inner = _appell.fit_py(_paths(recording), None, r.text, r.label, read, fit_opts, threads)
    result = FitResult(inner)
    _warn_fps([inner.fps_note()])
    if plot is not None:
        result.plot(_path(plot, "plot"))
    if friction_plot is not None:
        result.friction_plot(_path(friction_plot, "friction_plot"))
    return result


def fit_joint(
    releases: Union[PathLike, Sequence[Union[PathLike, Sequence[PathLike]]]],
    rig: Union[Rig, PathLike],
    *,
    same_camera: bool = False,
    keep_going: bool = False,
    plot: Optional[PathLike] = None,
    threads: Optional[int] = None,
    **options,
) -> JointResult:
    """Fit releases of one rig together (``appell fit --joint``): the friction law, tilt and
    pendulum shared, each release's state its own. ``releases`` is a directory of recordings
    or a list of releases (a file, or a Tracker pair as a list of two)."""
    r = _rig(rig)
    read, fit_opts = _split(options, "fit_joint")
    if _is_path(releases) and os.path.isdir(_path(releases, "releases")):
        directory, lists = _path(releases, "releases"), []
    else:
        directory = None
        lists = [_paths(rel, f"releases[{i}]") for i, rel in enumerate(_strings(releases))]
    inner = _appell.fit_joint_py(
        directory, lists, r.text, r.label, read, fit_opts, bool(same_camera), bool(keep_going),
        threads,
    )
    result = JointResult(inner)
    _warn_fps(inner.fps_notes())
    if plot is not None:
        result.plot(_path(plot, "plot"))
    return result


def _toml_text(source: PathLike, name: str) -> tuple:
    label = _path(source, name)
    return _appell.read_toml_py(label), label


class Simulation:
    """A simulated run: ``columns`` (numpy arrays t, x, theta, x_dot, theta_dot, the markers,
    and energy when the scene asks), ``mode`` per sample, ``events``, ``timeline``."""

    def __init__(self, d: dict):
        self.columns = {k: np.frombuffer(v, dtype=np.float64) for k, v in d["columns"].items()}
        self.mode = np.array(d["mode"], dtype=object)
        self._json = d["json"]
        self.timeline = d["timeline"]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.mode if name == "mode" else self.columns[name]

    def to_dict(self) -> dict:
        """``appell simulate --json``."""
        return json.loads(self._json)

    @property
    def events(self) -> list:
        return self.to_dict().get("events", [])

    def to_pandas(self):
        import pandas as pd

        df = pd.DataFrame(self.columns)
        df.insert(1, "mode", self.mode)
        return df

    def __repr__(self) -> str:
        return f"<Simulation {len(self.mode)} samples, {len(self.events)} events>"


def simulate(scene: PathLike, *, frame_rate: Optional[float] = None) -> Simulation:
    """Simulate a scene file, sampled at its ``[output] frame_rate`` (else ``frame_rate``, else
    1000 Hz as ``appell simulate --out``)."""
    text, label = _toml_text(scene, "scene")
    return Simulation(
        _appell.simulate_py(text, label, None if frame_rate is None else float(frame_rate))
    )


class _Figure:
    #: What the figure shows, for the notebook's image.
    _figure_alt = "the figure"
    _json: str
    _text: str
    _svg: str

    def to_dict(self) -> dict:
        return json.loads(self._json)

    def report(self) -> str:
        return self._text

    def svg(self) -> str:
        return self._svg

    def _repr_html_(self) -> str:
        figure = _svg_img(self._svg, self._figure_alt)
        return f"<div><pre>{html.escape(self._text)}</pre>{figure}</div>"


class Plan(_Figure):
    """Ranked releases that make the wanted transitions observable (``appell plan``)."""

    _figure_alt = "the proposed releases in the (theta, theta') plane over the stick region"

    def __init__(self, parts):
        self._json, self._text, self._svg = parts

    @property
    def proposals(self) -> list:
        """The proposed releases, best first (predicted standard error of mu)."""
        return self.to_dict().get("proposals", [])

    def __repr__(self) -> str:
        return f"<Plan {len(self.proposals)} proposals>"


def plan(
    spec: PathLike,
    after: Union[None, PathLike, FitResult, JointResult] = None,
    *,
    plot: Optional[PathLike] = None,
) -> Plan:
    """Plan releases from a plan file; ``after`` is an earlier fit (a result, or its JSON file)
    whose values and covariance become the plan's prior; ``plot`` writes the figure (SVG or
    PNG)."""
    text, label = _toml_text(spec, "spec")
    after_json, after_label, after_path = None, "", None
    if isinstance(after, _Result):
        after_json, after_label = after._inner.json(), "the fit given as after"
    elif after is not None:
        after_path = after_label = _path(after, "after")
    return Plan(
        _appell.plan_py(
            text, label, after_json, after_label, after_path,
            None if plot is None else _path(plot, "plot"),
        )
    )


def synth(
    scene: PathLike,
    output: Optional[PathLike] = None,
    *,
    fps: float = 1000.0,
    duration: Optional[float] = None,
    noise: float = 0.0,
    dropout: float = 0.0,
    outliers: float = 0.0,
    outlier_size: float = 0.05,
    seed: int = 0,
) -> Recording:
    """A synthetic recording of a scene with a known mu (``appell synth``); written to
    ``output`` (CSV or MCAP by extension) when given. ``metadata['truth']`` holds the truth."""
    text, label = _toml_text(scene, "scene")
    d = _appell.synth_py(
        text, label, float(fps), None if duration is None else float(duration), float(noise),
        float(dropout), float(outliers), float(outlier_size), int(seed),
        None if output is None else _path(output, "output"),
    )
    rec = Recording._from_rust(d)
    rec.metadata["truth"] = {k: _number(v) for k, v in d["truth"].items()}
    rec.metadata["stopped_at"] = d["stopped_at"]
    return rec


def _number(text: str):
    """A truth value as a number where it is one (the files store text)."""
    try:
        return float(text)
    except ValueError:
        return text


class Regions(_Figure):
    """The stick and sliding regions, the paradox band and phase portraits (``appell
    regions``)."""

    _figure_alt = "the stick and sliding regions, the paradox band and phase portraits"

    def __init__(self, parts):
        self._json, self._text, self._svg = parts

    def __repr__(self) -> str:
        return "<Regions>"


def regions(
    rig: Union[Rig, PathLike],
    *,
    trajectories: int = 8,
    duration: float = 3.0,
    plot: Optional[PathLike] = None,
) -> Regions:
    """The rig's regions in the (theta, theta') plane with ``trajectories`` phase portraits;
    ``plot`` writes the figure (SVG or PNG)."""
    r = _rig(rig)
    return Regions(
        _appell.regions_py(
            r.text, r.label, int(trajectories), float(duration),
            None if plot is None else _path(plot, "plot"),
        )
    )


def _fit_row(path, rig_text, rig_label, read, fit_opts, threads=1) -> dict:
    """One recording of fit_many: a table row, the error in its own column (never raised)."""
    files = _paths(path)
    row = {"recording": ",".join(files)}
    try:
        inner = _appell.fit_py(files, None, rig_text, rig_label, read, fit_opts, threads)
        d = json.loads(inner.json())
        mu = d.get("mu_kinetic") or {}
        lo, hi = _interval(mu)
        row.update(
            mu_kinetic=mu.get("value"),
            stderr=mu.get("stderr"),
            ci95_low=lo,
            ci95_high=hi,
            limited_by_model=d.get("limited_by_model"),
            answer=d.get("answer"),
            error=None,
            result=d,
        )
    except (ValueError, RuntimeError) as e:
        row.update(
            mu_kinetic=None, stderr=None, ci95_low=None, ci95_high=None,
            limited_by_model=None, answer=None, error=str(e), result=None,
        )
    return row


def _fit_rows(paths, rig_text, rig_label, read, fit_opts, threads=1) -> list:
    """One task of fit_many: a batch of recordings, a row each."""
    return [_fit_row(p, rig_text, rig_label, read, fit_opts, threads) for p in paths]


#: How long ``fit_many`` waits to connect to a scheduler given by its address.
CONNECT_SECONDS = 10


def _connect(address: str):
    """A dask.distributed client connected to the scheduler at ``address`` (the caller closes
    it); a TypeError naming the fix without dask.distributed, a ValueError naming the address
    when no scheduler answers in ``CONNECT_SECONDS``."""
    try:
        from distributed import Client
    except ImportError:
        raise TypeError(
            f"fit_many: client={address!r} is a scheduler's address, and connecting to it needs "
            "dask.distributed: pip install 'appell[dask]', or pass a dask.distributed.Client"
        ) from None
    try:
        return Client(address, timeout=CONNECT_SECONDS)
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"fit_many: client={address!r}: cannot connect to a scheduler: {e}") from e


def fit_many(
    paths: Iterable[Union[PathLike, Sequence[PathLike]]],
    rig: Union[Rig, PathLike],
    client=None,
    *,
    as_pandas: Optional[bool] = None,
    threads: Optional[int] = 1,
    batch: Optional[int] = None,
    **options,
):
    """Fit each recording on its own and gather one row per recording: ``recording``,
    ``mu_kinetic``, ``stderr``, ``ci95_low``, ``ci95_high``, ``limited_by_model``,
    ``answer``, ``error`` (a recording that cannot be fitted is a row with its error) and
    ``result`` (the full ``--json``).

    ``client`` is a ``dask.distributed.Client`` (``Client(LocalCluster())``, or
    ``Client("tcp://scheduler:8786")`` on a cluster), or a scheduler's address (a client is
    connected for the call and closed after it): each recording is one task. Without
    one, the recordings are fitted here, one after another. ``batch`` recordings make one
    task (default: about eight tasks per worker, since a short recording's fit of 10-20 ms
    is cheaper than a task's round trip through the scheduler; ``batch=1`` makes each
    recording a task of its own, best when recordings differ much in length). Each fit runs on ``threads``
    threads of its own (1: a task is one core, as Dask schedules it; None: the shared pool).
    The table is a pandas DataFrame when pandas is installed (``as_pandas=False``: a list of
    dicts)."""
    r = _rig(rig)
    read, fit_opts = _split(options, "fit_many")
    paths = list(paths)
    if client is None:
        rows = [_fit_row(p, r.text, r.label, read, fit_opts, threads) for p in paths]
    elif isinstance(client, str):
        with _connect(client) as connected:
            return fit_many(
                paths, r, connected, as_pandas=as_pandas, threads=threads, batch=batch,
                **options,
            )
    else:
        if not all(hasattr(client, m) for m in ("scheduler_info", "map", "gather")):
            raise TypeError(
                "fit_many: client must be a dask.distributed.Client or a scheduler's address "
                f"(\"tcp://host:8786\"), got {type(client).__name__} {client!r}"
            )
        if batch is None:
            workers = max(1, len(client.scheduler_info().get("workers", {})))
            batch = max(1, -(-len(paths) // (8 * workers)))
        if int(batch) < 1:
            raise ValueError(f"fit_many: batch must be at least 1, got {batch}")
        chunks = [paths[i : i + int(batch)] for i in range(0, len(paths), int(batch))]
        futures = client.map(
            _fit_rows, chunks, rig_text=r.text, rig_label=r.label, read=read,
            fit_opts=fit_opts, threads=threads, pure=False,
        )
        rows = [row for chunk in client.gather(futures) for row in chunk]
    if as_pandas is False:
        return rows
    try:
        import pandas as pd
    except ImportError:
        if as_pandas:
            raise
        return rows
    return pd.DataFrame(rows)
