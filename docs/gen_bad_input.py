"""Write docs/bad-input.md: every class of bad input tried, and the message ppfab prints for it.

    python docs/gen_bad_input.py

The cases are those of ``tests/bad_inputs.py``; each row is also a test in ``tests/test_bad_input.py``.
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))


def main() -> None:
    from bad_inputs import CASES

    from fabrication.cli import main as ppfab

    lines = ["# Bad input and what ppfab says", "",
             "Every class of bad input that was tried, and the one line ppfab prints for it (exit code in the "
             "third column; paths shortened to `…/`). Each row is a test in `tests/test_bad_input.py`, generated "
             "by `python docs/gen_bad_input.py`. No row writes an output folder.", "",
             "| input | what is wrong | exit | message |", "|---|---|---|---|"]
    for case in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            d = Path(tmp)
            for name, text in case.files.items():
                (d / name).parent.mkdir(parents=True, exist_ok=True)
                (d / name).write_text(text)
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = ppfab(case.argv(d))
            msg = err.getvalue().strip().splitlines()[-1].replace(str(d) + "/", "…/")
            msg = msg.replace(str(HERE.parents[1] / "shared" / "data") + "/", "…/")
        if len(msg) > 330:
            msg = msg[:330] + " …"
        lines.append(f"| {case.kind} | {case.what} | {code} | `{msg.replace('|', '/')}` |")
    (HERE / "bad-input.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(HERE / "bad-input.md")


if __name__ == "__main__":
    main()
