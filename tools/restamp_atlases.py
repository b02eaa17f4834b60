"""A developer's tool: stamp the shipped atlases with this code's fingerprints, after a change
to what the fingerprints hash (the way they hash it, or the modules they cover) that changes no
node, without rebuilding them (about 25 min of CPU on 2 cores):

    .venv/bin/python tools/restamp_atlases.py

Only the stamps change: each atlas's node arrays are written back as they were (checked against
tests/data/reference/atlas-hashes.json). The new stamps are kept only if the suite's checks of
the shipped atlases pass with them (current, and some nodes of each solved again here, the same
gaits within the plans' tolerances: tests/test_reference_figures.py); otherwise every file is
restored, and the atlases need `biped-gait atlas build`.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from biped_gait.core.gait.atlas import atlas_path, write_archive  # noqa: E402
from biped_gait.core.gait.configurations import GaitMode  # noqa: E402
from biped_gait.core.gait.fingerprint import model_fingerprint, source_fingerprint  # noqa: E402
from biped_gait.core.gait.turning_atlas import turning_atlas_path, turning_fingerprint  # noqa: E402
from biped_gait.core.model.params import load_params, shipped_param_names  # noqa: E402
from tests.reference_figures import DATA, atlas_hashes  # noqa: E402

CHECKS = ["tests/test_atlas.py::test_the_shipped_atlases_are_current",
          "tests/test_reference_figures.py::test_the_shipped_atlases_nodes_are_gaits_of_this_machine",
          "tests/test_reference_figures.py::test_the_shipped_turning_atlases_nodes_are_strides_of_this_machine"]


def stamps() -> dict[Path, dict[str, str]]:
    """Each shipped atlas file and the stamps this code gives it."""
    out = {}
    for name in shipped_param_names():
        params = load_params(name)
        for mode in GaitMode:
            out[atlas_path(params, mode)] = {"fingerprint": model_fingerprint(params),
                                             "source": source_fingerprint(params)}
            if params.joints.lateral_hips:
                out[turning_atlas_path(params, mode)] = {"fingerprint": turning_fingerprint(params)}
    return out


def restamp(path: Path, stamp: dict[str, str]) -> bool:
    """Write ``stamp`` into the meta of the atlas at ``path``, its arrays unchanged; False if it
    had it already."""
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["meta"]))
        arrays = {name: data[name] for name in data.files if name != "meta"}
    if all(meta.get(key) == value for key, value in stamp.items()):
        return False
    write_archive(path, {**meta, **stamp}, arrays)
    return True


def main() -> int:
    originals = {path: path.read_bytes() for path in stamps()}
    changed = [path.name for path, stamp in stamps().items() if restamp(path, stamp)]
    if not changed:
        print("every shipped atlas has this code's stamps")
        return 0
    same = atlas_hashes() == json.loads((DATA / "atlas-hashes.json").read_text())
    checked = same and subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", *CHECKS], cwd=ROOT).returncode == 0
    if not checked:
        for path, content in originals.items():
            path.write_bytes(content)
        print("tools/restamp_atlases.py: " + ("the shipped atlases' nodes do not solve the same here"
                                              if same else "a node array changed") + ": every file restored; "
              "rebuild the atlases with `biped-gait atlas build`", file=sys.stderr)
        return 1
    print(f"re-stamped {len(changed)} shipped atlases ({', '.join(changed)}), their nodes checked")
    return 0


if __name__ == "__main__":
    sys.exit(main())
