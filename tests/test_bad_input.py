"""Each class of bad input gets one clear line naming what is wrong, a non-zero exit, no traceback and no
output folder (the table in docs/bad-input.md is generated from the same cases)."""

import pytest

from fabrication.cli import main

from bad_inputs import CASES


@pytest.mark.parametrize("case", CASES, ids=[f"{c.kind}:{c.what}" for c in CASES])
def test_bad_input(tmp_path, capsys, case):
    for name, text in case.files.items():
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(case.argv(tmp_path))
    err = capsys.readouterr().err
    assert code == case.code, err
    assert err.startswith("ppfab: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert case.message in err, err
    # nothing written beside the inputs (the output folder only appears on success)
    assert sorted(p.name for p in tmp_path.iterdir()) == before
