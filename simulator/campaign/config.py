"""What a campaign runs: its configuration, the parameters stored in ``campaign.json``, and the per-run seeds.

A campaign of ``N`` runs of one world draws run ``i``'s seed from the campaign seed alone::

    seed_i = SeedSequence(campaign_seed, spawn_key=(i,)).generate_state(1)[0]     (a uint32, as a Python int)

so any subset of runs, in any order, on any machine, gets the same seeds, and run ``i`` of two campaigns with the same
seed is the same run bit for bit (:mod:`simulator.seeding` derives every component's stream from the run seed).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from worlds.loader import LoadedWorld

__all__ = ["FAILED", "CampaignConfig", "CampaignError", "CampaignParams", "RunTask", "RunReport", "run_seed",
           "run_dir_name"]

FAILED = ("error", "diverged")
"""Statuses of a run that ended for good without completing."""


class CampaignError(ValueError):
    """A campaign that cannot start: bad parameters, or a resume whose parameters differ from the stored ones."""


def run_seed(campaign_seed: int, index: int) -> int:
    """Seed of run ``index`` of a campaign seeded ``campaign_seed``: ``SeedSequence(seed, spawn_key=(index,))``."""
    if campaign_seed < 0:
        raise ValueError(f"campaign_seed must be >= 0, got {campaign_seed}")
    if index < 0:
        raise ValueError(f"index must be >= 0, got {index}")
    return int(np.random.SeedSequence(campaign_seed, spawn_key=(index,)).generate_state(1)[0])


def run_dir_name(index: int) -> str:
    """Run directory of run ``index``, relative to the campaign directory: ``runs/run-00042``."""
    return f"runs/run-{index:05d}"


@dataclass(frozen=True, kw_only=True)
class RunTask:
    """One run as a worker process receives it (picklable: plain values only).

    Attributes
    ----------
    index : int
        Run index in the campaign, 0-based.
    seed : int
        Run seed (see :func:`run_seed`).
    world : str
        World file path (resolved once by the parent).
    overrides : tuple of str
        ``key.path=value`` overrides, as ``--set``.
    duration_s : float
        Simulated duration, s.
    out_dir : str
        The run directory (absolute).
    """

    index: int
    seed: int
    world: str
    overrides: tuple[str, ...]
    duration_s: float
    out_dir: str


@dataclass(frozen=True, kw_only=True)
class RunReport:
    """What came back from one run: one line of ``campaign.jsonl``.

    Attributes
    ----------
    index, seed : int
        As in the :class:`RunTask`.
    status : str
        ``completed``, ``error``, ``diverged`` (the physics blew up: a failed run, like ``error``) or ``interrupted``
        (interrupted runs are not journaled: they run again on resume).
    error : str | None
        ``"ExceptionType: message"`` when the run failed, else None.
    wall_time_s : float
        Wall time of the run in its worker, s (0 when the worker died).
    metrics : dict
        The run's ``metrics.json`` flattened to dotted keys (``targets.car1.uav1.position_rmse_m``).
    run_dir : str
        Run directory relative to the campaign directory.
    files : dict | None
        ``{path in the run directory: [size in bytes, SHA-256 hex]}`` of the run's files when the campaign process
        journaled it, checked on resume (:mod:`simulator.campaign.verify`); None in lines written before it existed.
    """

    index: int
    seed: int
    status: str
    error: str | None
    wall_time_s: float
    metrics: dict[str, Any] = field(default_factory=dict)
    run_dir: str = ""
    files: dict[str, list] | None = None

    def __post_init__(self) -> None:
        if self.status not in ("completed", *FAILED, "interrupted"):
            raise ValueError(f"RunReport.status must be completed, error, diverged or interrupted, got "
                             f"{self.status!r}")
        for name, kind in (("index", int), ("seed", int), ("metrics", dict), ("run_dir", str)):
            if not isinstance(getattr(self, name), kind) or isinstance(getattr(self, name), bool):
                raise ValueError(f"RunReport.{name} must be {kind.__name__}, got {getattr(self, name)!r:.60}")
        if self.files is not None and not (isinstance(self.files, dict) and all(
                isinstance(k, str) and isinstance(v, list) and len(v) == 2 and isinstance(v[0], int)
                and isinstance(v[1], str) for k, v in self.files.items())):
            raise ValueError(f"RunReport.files must map paths to [size, sha256], got {self.files!r:.60}")

    @property
    def finished(self) -> bool:
        """True when the run need not run again (it completed or failed for good)."""
        return self.status == "completed" or self.status in FAILED

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunReport:
        keys = ("index", "seed", "status", "error", "wall_time_s", "metrics", "run_dir", "files")
        return cls(**{k: data[k] for k in keys if k in data})


RunFunction = Callable[[RunTask], RunReport]


@dataclass(frozen=True, kw_only=True)
class CampaignConfig:
    """A Monte Carlo campaign: ``runs`` seeded runs of one world.

    Attributes
    ----------
    world : str | Path
        A shipped world's name or a world file path.
    runs : int
        Number of runs ``N`` (indices ``0 .. N-1``).
    out_dir : Path
        Campaign directory: ``campaign.json``, ``campaign.jsonl``, ``runs/run-NNNNN/``, ``summary.json``,
        ``summary.md``.
    seed : int | None
        Campaign seed; None = the world's ``sim.seed``.
    duration_s : float | None
        Simulated seconds per run; None = the world's ``sim.duration_s``.
    overrides : tuple of str
        ``key.path=value`` world overrides applied to every run.
    workers : int | None
        Local worker processes (None = all cores); with Ray, the most runs in flight (None = as many as Ray schedules).
    ray_address : str | None
        None = local process pool; ``"auto"`` = an existing local Ray cluster, or a new local one; else a Ray address.
    progress : bool
        Show a progress bar (runs done / failed).
    run_fn : callable | None
        ``f(RunTask) -> RunReport`` run in the workers; None = :func:`simulator.campaign.worker.run_one`. It must be
        a module-level function (workers import it by name).
    """

    world: str | Path
    runs: int
    out_dir: Path
    seed: int | None = None
    duration_s: float | None = None
    overrides: tuple[str, ...] = ()
    workers: int | None = None
    ray_address: str | None = None
    progress: bool = False
    run_fn: RunFunction | None = None

    def __post_init__(self) -> None:
        if isinstance(self.runs, bool) or not isinstance(self.runs, int) or self.runs < 1:
            raise ValueError(f"CampaignConfig.runs must be an int >= 1, got {self.runs!r}")
        if self.seed is not None and self.seed < 0:
            raise ValueError(f"CampaignConfig.seed must be >= 0, got {self.seed}")
        if self.duration_s is not None and not self.duration_s > 0:
            raise ValueError(f"CampaignConfig.duration_s must be > 0 s, got {self.duration_s}")
        if self.workers is not None and self.workers < 1:
            raise ValueError(f"CampaignConfig.workers must be >= 1, got {self.workers}")
        if self.ray_address is not None and not str(self.ray_address).strip():
            raise ValueError(f"CampaignConfig.ray_address must be 'auto' or an address, got {self.ray_address!r}")
        object.__setattr__(self, "out_dir", Path(self.out_dir))
        object.__setattr__(self, "overrides", tuple(str(o).strip() for o in self.overrides))


@dataclass(frozen=True, kw_only=True)
class CampaignParams:
    """The parameters that define a campaign's runs, stored in ``campaign.json``; a resume must match them.

    Attributes
    ----------
    world : str
        The world as given (name or path).
    world_path : str
        The world file it resolved to.
    world_sha256 : str
        SHA-256 of that file's bytes (a world edited between runs of one campaign is caught).
    overrides : list of str
        World overrides, in order.
    seed : int
        Campaign seed (resolved).
    duration_s : float
        Simulated seconds per run (resolved), s.
    runs : int
        Number of runs.
    """

    world: str
    world_path: str
    world_sha256: str
    overrides: list[str]
    seed: int
    duration_s: float
    runs: int

    @classmethod
    def resolve(cls, config: CampaignConfig, loaded: LoadedWorld) -> CampaignParams:
        """Fill in the world's seed and duration where the config leaves them open."""
        sim = loaded.world.sim
        return cls(world=str(config.world), world_path=str(loaded.path),
                   world_sha256=hashlib.sha256(Path(loaded.path).read_bytes()).hexdigest(),
                   overrides=list(config.overrides),
                   seed=int(sim.seed if config.seed is None else config.seed),
                   duration_s=float(sim.duration_s if config.duration_s is None else config.duration_s),
                   runs=config.runs)

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    def differences(self, stored: dict[str, Any]) -> list[str]:
        """What differs from a stored ``campaign.json`` (``world`` as typed may differ if it names the same file).

        More runs than stored is no difference: a campaign is extended (run ``r``'s seed depends on ``r`` and the base
        seed alone, so the stored runs are the first runs of the longer campaign). Fewer is, as the stored runs beyond
        them would be dropped."""
        mine = self.to_json()
        out = []
        for key in ("world_path", "world_sha256", "overrides", "seed", "duration_s", "runs"):
            if key not in stored:
                out.append(f"{key}: missing from campaign.json, this call gives {mine[key]!r}")
            elif key == "runs" and isinstance(stored[key], int) and not isinstance(stored[key], bool) \
                    and mine[key] > stored[key]:
                continue
            elif stored[key] != mine[key]:
                extra = " (a campaign can be extended with more runs, not cut)" if key == "runs" else ""
                out.append(f"{key}: campaign.json has {stored[key]!r}, this call gives {mine[key]!r}{extra}")
        return out
