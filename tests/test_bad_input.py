"""Each class of bad input gets one clear line naming what is wrong, a non-zero exit, no traceback and no
output folder; the cases that must work despite hostile input (signals, killed runs, text that could break a
file) exit as documented and leave a verified folder or nothing.  The table in docs/bad-input.md is generated
from the same cases (``tests/bad_inputs.py``); cases that need one run in a separate process."""

import pytest

from bad_inputs import CASES, prepare_case, run_case


@pytest.mark.parametrize("case", CASES, ids=[f"{c.kind}:{c.what}" for c in CASES])
def test_bad_input(tmp_path, case):
    prepare_case(case, tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = run_case(case, tmp_path, prepared=True)
    assert code == case.code, err
    assert "Traceback" not in err and "Warning" not in err, err
    if case.code != 0:
        assert err.startswith("ppfab: ") and err.count("\n") == 1, err
        assert case.message in err, err
    else:
        assert err == "", err
        assert case.message in out, out
    if case.check is not None:
        case.check(tmp_path)
    # nothing written beside the inputs (the output folder only appears on success)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(set(before) | set(case.new_files))
