"""Whether a case file's ``run.target`` can mean anything for it: ``camopt validate``'s
warnings (a run still runs; its success rate is then 0 or measured against another
case's objective)."""

from __future__ import annotations

from camopt.config import LoadedConfig
from camopt.core.problem import Problem


def target_warnings(config: LoadedConfig, problem: Problem) -> list[str]:
    """``<file>: run.target: <what>`` lines: a target below the objective's floor (no
    design can reach it), or one inherited through ``extends`` from a file whose
    ``[case]`` differs (its objective or feasible set is another case's)."""
    target = config.run.target
    if target is None:
        return []
    found = []
    floor = problem.objective_floor()
    if floor is not None and target < floor.value:
        found.append(f"{config.path}: run.target: {target:g} is below {floor.value:g}, the "
                     f"least {problem.objective_name} any design can reach ({floor.reason}): "
                     "no repeat can succeed")
    base = config.inherited("run", "target")
    if base is not None:
        theirs = base.merged.get("case") or {}
        ours = config.data.get("case") or {}
        changed = sorted(k for k in {*theirs, *ours} if theirs.get(k) != ours.get(k))
        if changed:
            shown = ", ".join(changed[:6]) + (f" and {len(changed) - 6} more"
                                              if len(changed) > 6 else "")
            found.append(f"{config.path}: run.target: {target:g} is inherited from "
                         f"{base.path}, whose [case] differs ({shown}): a target for another "
                         "objective or feasible set; set run.target in this file")
    return found
