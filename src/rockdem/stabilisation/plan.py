"""The stabilisation study of a model file: measures, designs and stages in one report.

:func:`study` runs what the file's ``stabilisation`` section asks for;
:meth:`Study.tables` gives plain rows for the report; :func:`save_pictures`
draws one picture per trial.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ModelWarning
from ..model import Model
from ..results import FactorOfSafety, format_factor
from ..units import parse_units
from . import _edit, _progress
from .measures import MeasureComparison, compare_measures
from .removal import Stabilisation, describe, meets, rate, stabilise
from .stages import Excavation, Stage, excavate_in_stages

__all__ = ["DesignTrial", "Study", "save_pictures", "study"]


@dataclass(frozen=True, eq=False)
class DesignTrial:
    """A removal design of the file (``stabilisation.trials``), rated."""

    name: str
    model: Model
    removed_blocks: tuple[int, ...]
    removed_area: float
    fos: FactorOfSafety
    reached: bool
    then: Stabilisation | None  # further removal to the target (``stabilise: true``)
    #: what the removal took besides rock: bolts, loads (see :func:`_edit.removal_notes`)
    notes: tuple[str, ...] = ()

    @property
    def total_removed_area(self) -> float:
        """Design removal plus the further removal it needed."""
        if self.then is None:
            return self.removed_area
        return self.removed_area + self.then.removed_area

    @property
    def total_removed_blocks(self) -> int:
        return len(self.removed_blocks) + (len(self.then.removed_blocks) if self.then else 0)


@dataclass(frozen=True, eq=False)
class Study:
    """Everything ``rockdem stabilise`` computes for one model."""

    target: float
    comparison: MeasureComparison
    designs: tuple[DesignTrial, ...]
    excavation: Excavation | None

    @property
    def removal(self) -> Stabilisation | None:
        return self.comparison.removal

    def tables(self) -> dict[str, list[dict]]:
        """Rows of the report tables: ``removal`` (each trial), ``measures``,
        ``designs`` and ``stages``."""
        out: dict[str, list[dict]] = {"measures": self.comparison.rows()}
        if self.removal is not None:
            out["removal"] = [
                {
                    "trial": t.number,
                    "round": t.round,
                    "label": t.label,
                    "blocks_removed": list(t.removed_blocks),
                    "n_removed": len(t.removed_blocks),
                    "area_removed": t.removed_area,
                    "factor_of_safety": t.factor,
                    "fos_text": describe(t.fos),
                    "mode": t.fos.mode,
                    "reaches_target": meets(t.fos, self.target),
                    "accepted": t.accepted,
                    "mechanism": list(t.mechanism),
                    "boundary": _boundary(t.fos),
                }
                for t in self.removal.trials
            ]
        out["designs"] = [
            {
                "design": d.name,
                "blocks_removed": list(d.removed_blocks),
                "area_removed": d.removed_area,
                "factor_of_safety": _factor(d.fos),
                "fos_text": describe(d.fos),
                "reaches_target": d.reached,
                "further_blocks": list(d.then.removed_blocks) if d.then else [],
                "total_area_removed": d.total_removed_area,
                "further_reached": d.then.reached if d.then else None,
                "note": "; ".join(d.notes),
                "boundary": _boundary(d.fos),
            }
            for d in self.designs
        ]
        if self.excavation is not None:
            out["stages"] = [
                {
                    "stage": s.number,
                    "name": s.name,
                    "stable": s.stable,
                    "area_removed": s.removed_area,
                    "new_failed_joints": len(s.new_failures),
                    "unstable_blocks": [int(i) for i in s.analysis.unstable_blocks],
                }
                for s in self.excavation.stages
            ]
            out["stage_failures"] = self.excavation.failures_by_stage()
        return out


def _boundary(fos: FactorOfSafety) -> str:
    """Where the design's critical mechanism reaches a fixed side of the model
    ("" if nowhere): its factor is then set by where the section was cut
    (perpendicular-joints, round 2: FS 13.8 for the whole mass sliding on the
    model's base, not a word of it beside the table)."""
    from ..modes import boundary_warnings

    a = fos.failed_analysis
    return "" if a is None else "; ".join(boundary_warnings(a))


def _factor(fos: FactorOfSafety) -> float | None:
    if fos.value is not None:
        return float(fos.value)
    return float(fos.bracket[0]) if fos.mode == "no-failure" else None


def _removal_kw(r) -> dict:
    return {"blocks": list(r.blocks), "regions": list(r.regions), "profile": r.profile}


def study(
    model: Model,
    cfg,
    *,
    target_fos: float | None = None,
    support: bool = True,
    stages: bool = True,
    width: float = 0.01,
    progress: Callable[[str], None] | None = None,
) -> Study:
    """Run the stabilisation study a model file describes.

    Parameters
    ----------
    model : Model
    cfg : rockdem.config.ModelFile
        Its validated file (the ``stabilisation`` section is read).
    target_fos : float, optional
        Overrides ``stabilisation.target_fos``.
    support, stages : bool
        Include the support-force search and the excavation stages.
    progress : callable, optional
        Called with a one-line note (``"support force: staged analysis 3 with
        a force of 12.5"``) at every search and analysis of the study.
    """
    with _progress.reporting(progress):
        return _study(model, cfg, target_fos, support, stages, width)


def _bolting(spec) -> dict | None:
    """The bolt-pattern keywords of a `stabilisation.bolts` section."""
    if spec is None:
        return None
    kw = spec.model_dump()
    kw["bond_strength"] = np.inf if kw["bond_strength"] is None else kw["bond_strength"]
    return kw


def _study(model, cfg, target_fos, support, stages, width) -> Study:
    spec = cfg.stabilisation
    units = parse_units(getattr(cfg, "units", ""))
    target = float(target_fos if target_fos is not None else spec.target_fos)
    sup = spec.support
    comparison = compare_measures(
        model,
        target,
        berm=[tuple(p) for p in spec.berm] if spec.berm else None,
        support=support,
        support_at=tuple(sup.at) if sup is not None and sup.at is not None else None,
        support_angle=sup.angle if sup is not None else 195.0,
        support_largest=sup.largest if sup is not None else None,
        bolting=_bolting(spec.bolts),
        max_removal=spec.max_removal,
        max_rounds=spec.max_rounds,
        width=width,
        units=units,
    )
    designs = []
    for t in spec.trials:
        m = _edit.apply_removal(model, **_removal_kw(t.remove))
        ids, area = _edit.removed_between(model, m)
        took = _edit.removal_notes(model, m)  # the loads and bolts on the rock it removes
        if took:
            warnings.warn(ModelWarning(f"design {t.name}: {'; '.join(took)}"), stacklevel=2)
        with _progress.stage(f"design {t.name}"):
            f = rate(m, width=width)
        then = None
        if t.stabilise and not meets(f, target):
            # the limit on removal holds for the slope as designed: what the
            # trial removed counts (found by fuzzing: a 1% limit, 20% removed)
            rock = float(model.blocks.area[~model.blocks.fixed].sum())
            allowed = (spec.max_removal * rock - area) / max(rock - area, 1e-300)
            with _progress.stage(f"design {t.name}, further removal"):
                then = stabilise(
                    m,
                    target,
                    max_rounds=spec.max_rounds,
                    max_removal=min(max(allowed, 1e-12), 1.0),
                    smallest_set=spec.smallest_set,
                    width=width,
                    units=units,
                )
        designs.append(DesignTrial(t.name, m, ids, area, f, meets(f, target), then, took))
    excavation = None
    if stages and spec.stages:
        with _progress.stage("excavation stages"):
            excavation = excavate_in_stages(
                model, [Stage(s.name, **_removal_kw(s.remove)) for s in spec.stages]
            )
    return Study(target, comparison, tuple(designs), excavation)


def save_pictures(result: Study | Stabilisation, folder, *, dpi: int = 110) -> list[Path]:
    """One picture per removal trial (and per stage): the failure state of the
    design (mechanism shaded), the removed rock outlined in dashes.

    Returns the files written (``trial-00.png``, ..., ``stage-00.png``, ...).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    removal = result if isinstance(result, Stabilisation) else result.removal
    files: list[Path] = []
    if removal is not None:
        original = removal.original.model
        for t in removal.trials:
            fig, ax = plt.subplots(figsize=(8, 5))
            trial_picture(t, original, removal.target, ax=ax)
            fig.tight_layout()
            path = folder / f"trial-{t.number:02d}.png"
            fig.savefig(path, dpi=dpi)
            plt.close(fig)
            files.append(path)
    if isinstance(result, Study) and result.excavation is not None:
        from ..plots import plot_failure

        for s in result.excavation.stages:
            fig, ax = plt.subplots(figsize=(8, 5))
            plot_failure(
                s.analysis,
                ax=ax,
                title=f"stage {s.number}: {s.name} "
                f"({'stable' if s.stable else 'unstable'} at "
                f"F = {format_factor(s.analysis.strength_factor)}, "
                f"{len(s.new_failures)} joints "
                f"{'failed in this stage' if s.stable else 'giving way'})",
            )
            fig.tight_layout()
            path = folder / f"stage-{s.number:02d}.png"
            fig.savefig(path, dpi=dpi)
            plt.close(fig)
            files.append(path)
    return files


def trial_picture(trial, original: Model, target: float, *, ax=None, title: str | None = None):
    """Draw one trial: its failure state at the critical factor, removed blocks dashed."""
    from matplotlib.collections import PolyCollection

    from ..analysis import analyse
    from ..plots import plot_failure

    if trial.fos.mode == "strength-independent":  # show the mechanism under the loads as they are
        shown = analyse(trial.model)
    else:
        shown = trial.fos.failed_analysis or trial.fos.stable_analysis
    if title is None:
        import textwrap

        # (a label naming the loads the removal took ran off the picture)
        label = textwrap.fill(f"trial {trial.number}: {trial.label}", 70)
        title = (
            f"{label}\n{len(trial.removed_blocks)} blocks "
            f"removed (area {trial.removed_area:.2f}), FS {describe(trial.fos)}, "
            f"target {target:g}\nstate shown at F = {format_factor(shown.strength_factor)}"
        )
    ax = plot_failure(shown, ax=ax, title=title)
    b = original.blocks
    removed = [
        v for v, i in zip(b.polygons(), b.ids, strict=True) if int(i) in set(trial.removed_blocks)
    ]
    if removed:
        import numpy as np

        verts = [np.asarray(p.exterior.coords) for p in removed]
        ax.add_collection(
            PolyCollection(
                verts,
                facecolors="none",
                edgecolors="0.4",
                linestyles="--",
                linewidths=0.8,
                gid="removed",
            )
        )
        ax.autoscale_view()
    return ax
