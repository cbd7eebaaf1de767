"""A SLURM job array that runs a study's runs: the cluster's scheduler does the scheduling.

:func:`write_script` writes ``DIR/sweep.sbatch``; ``sbatch DIR/sweep.sbatch`` submits it. Task
``i`` of the array runs the ``i``-th unfinished run of the study (the names are listed in the
script, in grid order) exactly as the local runner does (:mod:`pdfem.study.local`):
``pdfem run DIR/runs/<name>/case.toml --out DIR/runs/<name>``, with ``--restart`` from the
run's checkpoint if an earlier try left one, its output appended to the run's ``log.txt`` and
its exit status written to the run's ``status.json`` (:mod:`pdfem.study.folder`). A task whose
run is finished already does nothing, so the script can be submitted again after a failure or a
time limit: only what is left runs. Each task gets ``threads`` cores (``--cpus-per-task``) and
runs that many threads (``NUMBA_NUM_THREADS``, ``OMP_NUM_THREADS``). Options given to
``sbatch`` on its command line override the ``#SBATCH`` lines (``sbatch --time=4:00:00
--partition=long DIR/sweep.sbatch``).
"""

from __future__ import annotations

import shlex
import shutil
import sys
from pathlib import Path
from typing import Sequence

from pdfem.study.folder import STATUS, SweepFolder

SCRIPT = "sweep.sbatch"
"""The job-array script's name in the study folder."""


def pdfem_executable() -> str:
    """The ``pdfem`` of this installation (next to this Python), else ``pdfem`` on ``PATH``."""
    here = Path(sys.executable).parent / "pdfem"
    return str(here) if here.exists() else (shutil.which("pdfem") or "pdfem")


def script_text(folder: SweepFolder, names: Sequence[str], threads: int = 1,
                jobs: int | None = None, pdfem: str | None = None) -> str:
    """The job-array script that runs ``names`` of ``folder`` (module docstring).

    Parameters
    ----------
    folder
        The study folder (its case files written).
    names
        The runs of the array, task ``i`` runs ``names[i]``.
    threads
        Cores and threads per task.
    jobs
        Tasks running at once (the array's ``%`` limit); ``None``: as many as SLURM gives.
    pdfem
        The ``pdfem`` command the tasks run (default :func:`pdfem_executable`); the variable
        ``PDFEM`` overrides it when the job runs.
    """
    root = folder.root.resolve()
    limit = "" if jobs is None else f"%{jobs}"
    q = shlex.quote
    return "\n".join([
        "#!/bin/bash",
        f"# pdfem sweep: {len(names)} runs of the study in {root}, one array task per run.",
        f"# Submit: sbatch {q(str(root / SCRIPT))}   (sbatch options on its command line, e.g.",
        "# --time=4:00:00 --partition=long, override the #SBATCH lines below). Written by",
        "# pdfem sweep --slurm; write it again after changing the study.",
        "#SBATCH --job-name=pdfem-sweep",
        f"#SBATCH --array=0-{len(names) - 1}{limit}",
        "#SBATCH --ntasks=1",
        f"#SBATCH --cpus-per-task={threads}",
        f"#SBATCH --output={root / 'runs'}/slurm-%A_%a.log",
        "",
        f"PDFEM=${{PDFEM:-{q(pdfem or pdfem_executable())}}}",
        f"SWEEP={q(str(root))}",
        "RUNS=(" + " ".join(q(n) for n in names) + ")",
        'NAME="${RUNS[${SLURM_ARRAY_TASK_ID:?run this script with sbatch}]}"',
        'RUN="$SWEEP/runs/$NAME"',
        "# a run is finished when its status.json holds exit status 0 or 3 (a blow-up)",
        f'if grep -qE \'"exit_status": (0|3)[,}}]\' "$RUN/{STATUS}" 2>/dev/null; then',
        '    echo "pdfem sweep: $NAME finished before; nothing to do"',
        "    exit 0",
        "fi",
        f'THREADS="${{SLURM_CPUS_PER_TASK:-{threads}}}"',
        'export NUMBA_NUM_THREADS="$THREADS" OMP_NUM_THREADS="$THREADS"',
        'RESTART=""',
        'if [ -f "$RUN/checkpoint.h5" ]; then RESTART="--restart=$RUN/checkpoint.h5"; fi',
        f'rm -f "$RUN/{STATUS}"',
        'echo "\\$ pdfem run $RUN/case.toml --out $RUN $RESTART (task $SLURM_ARRAY_TASK_ID)" '
        '>> "$RUN/log.txt"',
        '"$PDFEM" run "$RUN/case.toml" --out "$RUN" ${RESTART:+"$RESTART"} >> "$RUN/log.txt" 2>&1',
        "STATUS=$?",
        f'printf \'{{"exit_status": %d}}\\n\' "$STATUS" > "$RUN/{STATUS}.tmp" && '
        f'mv "$RUN/{STATUS}.tmp" "$RUN/{STATUS}"',
        'exit "$STATUS"',
        ""])


def write_script(folder: SweepFolder, names: Sequence[str], threads: int = 1,
                 jobs: int | None = None) -> Path:
    """Write :func:`script_text` to ``DIR/sweep.sbatch``; its path."""
    path = folder.root / SCRIPT
    path.write_text(script_text(folder, names, threads, jobs))
    path.chmod(0o755)
    return path
