"""Write docs/bad-input.md: every class of bad input tried, and what ppfab says or does for it.

The table is generated; the sections after it (from the first ``## `` heading on) are written by hand and kept.

    python docs/gen_bad_input.py

The cases are those of ``tests/bad_inputs.py``; each row is also a test in ``tests/test_bad_input.py``,
run the same way (:func:`bad_inputs.run_case`: in-process, or in a separate process for FIFOs, devices,
real signals, killed and concurrent runs).
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))


def main() -> None:
    from bad_inputs import CASES, SHARED_DATA, run_case

    lines = ["# Bad input and what ppfab says", "",
             "Every class of bad input that was tried, and the one line ppfab prints for it (exit code in the "
             "third column; paths shortened to `…/`), or, for input that must be handled rather than refused, "
             "what happens (in italics). Each row is a test in `tests/test_bad_input.py`, generated "
             "by `python docs/gen_bad_input.py`; rows marked ⚙ run `ppfab` in a separate process (FIFOs and "
             "devices, real signals sent to a running build, a build killed with SIGKILL and run again, two "
             "builds at once). No refused row writes or damages an output folder.", "",
             "| input | what is wrong | exit | message |", "|---|---|---|---|"]
    for case in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            d = Path(tmp)
            code, out, err = run_case(case, d)
            text = (err.strip() or out.strip()).splitlines()
            msg = text[-1] if text and case.code != 0 else ""
            for root in (str(d.resolve()), str(d), str(SHARED_DATA)):
                msg = msg.replace(root + "/", "…/")
            msg = re.sub(r"pid [0-9]+", "pid …", msg)
        if len(msg) > 330:
            msg = msg[:330] + " …"
        shown = f"`{msg.replace('|', '/')}`" if msg else f"*{case.note}*"
        mark = " ⚙" if case.process else ""
        lines.append(f"| {case.kind} | {case.what}{mark} | {code} | {shown} |")
    target = HERE / "bad-input.md"
    old = target.read_text(encoding="utf-8").splitlines() if target.is_file() else []
    kept = next((old[k:] for k, line in enumerate(old) if line.startswith("## ")), [])   # hand-written sections
    target.write_text("\n".join(lines + ([""] + kept if kept else [])) + "\n", encoding="utf-8")
    print(HERE / "bad-input.md")


if __name__ == "__main__":
    main()
