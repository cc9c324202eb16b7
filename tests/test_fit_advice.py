"""What a build says when a robot's allowed transitions alone do not fit the board: the ways
its robot file can allow fewer. It said `allow = "one-level" or "one-limb"` to an unmeasured
robot that had one-level already."""

from __future__ import annotations

import pytest
from build_checks import cli


def _unmeasured(tmp_path, limbs: int, levels: int, allow: str):
    stars = ", ".join(f"{8.0 * (i + 1):g}" for i in range(levels - 1))
    text = ['[robot]\nname = "wide"\n']
    text += [f'[[limb]]\nname = "L{i}"\nlevels = {levels}\npsi_star_deg = [{stars}]\nactuator = "s{i}"\n'
             for i in range(limbs)]
    text += [f'[[actuator]]\nname = "s{i}"\nchannel = {i}\n' for i in range(limbs)]
    text += [f'[transitions]\nmatrix = "unmeasured"\nallow = "{allow}"\n', "[control]\ntick_hz = 200\n"]
    path = tmp_path / "wide.toml"
    path.write_text("\n".join(text), encoding="utf-8")
    return path


@pytest.mark.parametrize("limbs, levels, allow, advised, not_advised", [
    (7, 4, "one-level", [], ['allow = "one-level"', 'allow = "one-limb"']),  # 172,032: the narrowest rule already
    (5, 3, "any", ['allow = "one-limb": 2,430 transitions', 'allow = "one-level": 1,620 transitions'], []),
    (7, 3, "one-limb", ['allow = "one-level": 20,412 transitions'], ['allow = "one-limb"']),
])
def test_the_advice_names_only_rules_that_allow_fewer(tmp_path, capsys, limbs, levels, allow, advised, not_advised):
    path = _unmeasured(tmp_path, limbs, levels, allow)
    code, _out, err = cli(capsys, "-q", "build", path, "--board", "bluepill-f103", "--out", tmp_path / "fw")
    assert code == 2 and "allowed transitions alone take" in err, err
    assert "forbidden = [...] beside the allow it has" in err
    assert all(a in err for a in advised) and not any(n in err for n in not_advised), err
