"""Type stubs of the native module (python/src/): scenes, runs and sweeps of the Rust
library. Use the package's functions (``stickslip.run``, ``stickslip.sweep``); these are
their building blocks."""

from typing import Callable, Optional

__version__: str

# (column names, column bytes, kind names): f64 columns, ``junction`` uint32, ``kind`` uint8
# codes into the kind names.
_Columns = tuple[list[str], list[bytes], list[str]]

class Scene:
    """A validated scene. Immutable; pickles as its complete TOML text and name."""

    def __init__(self, text: str, name: str = "scene", overrides: list[str] = ...) -> None:
        """Reads TOML text, applies ``section.key=value`` overrides and validates.
        Raises ValueError with the CLI's one-line message."""
    @staticmethod
    def from_file(path: str, overrides: list[str] = ...) -> Scene:
        """Reads a scene file (its stem is the name), applies the overrides and validates."""
    def with_overrides(self, overrides: list[str]) -> Scene:
        """This scene with further overrides applied and validated."""
    @property
    def name(self) -> str: ...
    @property
    def seed(self) -> int: ...
    def stability_warning(self) -> Optional[str]:
        """The warning ``stickslip run`` prints for a fixed step beyond the plate
        integrator's stability limit, or None."""
    def to_toml(self) -> str:
        """The complete scene file (every field explicit); reads back to the same scene."""
    def to_json(self) -> str:
        """The resolved parameters as JSON (``parameters`` in summary.json)."""
    def __eq__(self, other: object) -> bool: ...

def run_to_dir(scene: Scene, out: str) -> tuple[str, Optional[_Columns], Optional[_Columns]]:
    """Runs the scene into the existing directory ``out`` (the CLI's files) and returns
    summary.json's text with the trace's and events' columns. Releases the GIL."""

def run_summary_json(scene_toml: str, name: str) -> str:
    """One run without files: summary.json's text. Releases the GIL."""

def parse_values(flag: str, text: str) -> list[str]:
    """The values of ``--values``, ``--range`` or ``--log-range`` (flag ``values``,
    ``range``, ``log-range``) as scene texts."""

class Sweep:
    """A prepared sweep: validated and seeded as ``stickslip sweep`` does; not run."""

    def __init__(
        self, base: Scene, axes: list[tuple[str, list[str], bool]], replicas: int, set: list[str] = ...
    ) -> None: ...
    def __len__(self) -> int: ...
    def runs(self) -> list[tuple[int, int, Scene]]:
        """Every run in order: (grid point, replica, scene with its derived seed)."""
    @property
    def params(self) -> list[str]: ...
    def describe(self, point: int) -> str: ...
    def outcome(
        self, summaries: list[str], wall_seconds: Optional[float] = None, workers: Optional[int] = None
    ) -> SweepOutcome:
        """The outcome from every run's summary.json text, in the order of ``runs()``."""
    def journal(self, out: str) -> SweepJournal:
        """Opens (or starts) the sweep's journal.jsonl in the existing directory ``out``,
        locked; a journal of another sweep or scene is a ValueError."""

class SweepJournal:
    def done(self) -> list[Optional[str]]:
        """Per run: its summary.json text if the journal held it when opened, else None."""
    def append(self, run: int, summary: str) -> None:
        """Appends a finished run (its summary.json text) as one synced line."""
    @property
    def path(self) -> str: ...

class SweepOutcome:
    def sweep_csv(self) -> str: ...
    def runs_csv(self) -> str: ...
    def sweep_json(self) -> str: ...
    def write(self, out: str) -> None:
        """Writes sweep.csv, runs.csv, sweep.svg and sweep.json into ``out``."""

class FrictionLaw:
    """A friction law built by the library (``stickslip friction-law``)."""

    def law_csv(self) -> str: ...
    def abaqus_inp(self) -> str: ...
    def ansys_mac(self) -> str: ...
    def law_json(self) -> str: ...
    def write(self, out: str) -> None:
        """Writes law.csv, abaqus.inp, ansys.mac and law.json into the existing directory ``out``."""

def friction_law(
    source: object, l0: Optional[float], t0: Optional[float], t_ref: Optional[float],
    normal_load: Optional[float], force_unit: Optional[float] = None, fit_degree: int = 2,
) -> FrictionLaw:
    """The law of a finished sweep's directory (a path) or of a ``SweepOutcome``: the
    arguments of :func:`stickslip.friction_law`. Raises ValueError with the CLI's message."""

def fit_run(scene_toml: str, name: str) -> float:
    """One run of a fit (no files): its mean friction per junction. RuntimeError naming
    the seed when the run fails."""

class Fit:
    """A prepared fit (``stickslip fit``): validated and seeded, not run."""

    def __init__(
        self, base: Scene, data: str, free: list[str], replicas: int = 4, friction_scale: float = 1.0,
        max_evaluations: int = 5000,
    ) -> None: ...
    def runs_per_evaluation(self) -> int: ...
    @property
    def free(self) -> list[str]: ...
    def run(
        self,
        out: str,
        simulate: Callable[[list[str], list[str]], list[float]],
        progress: Optional[Callable[[int, float, str], None]] = None,
    ) -> tuple[int, int]:
        """Runs the fit into the existing directory ``out`` (journal, lock, the four files);
        returns (evaluations, made now)."""
