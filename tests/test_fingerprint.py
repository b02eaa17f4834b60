"""What the atlases' fingerprints hash: the model code's tokens, the same on every Python version
(comments, blank lines, indentation widths and docstrings left out, a change of the code not),
over every core module the model and turning code import."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from biped_gait.core.gait.fingerprint import _CORE, MODEL_CODE, code_tokens
from biped_gait.core.gait.turning_atlas import TURNING_CODE

pytestmark = pytest.mark.core

CODE = '''"""A module."""
import math


class Rod:
    """A rod."""

    def mass(self, length):
        """Its mass (kg)."""
        return (2.0 * length  # density
                + math.pi)
'''
# The same code: other comments, blank lines, line breaks within brackets, indentation widths, docstrings.
SAME = '''import math  # what the rod needs
class Rod:
  def mass(self, length):
    "Its mass."
    # kg
    return (2.0 * length +


            math.pi)
'''


def test_comments_blank_lines_indentation_widths_and_docstrings_are_left_out():
    assert code_tokens(SAME) == code_tokens(CODE)
    assert code_tokens(CODE)[:9] == ["import", "math", "<NEWLINE>", "class", "Rod", ":", "<NEWLINE>", "<INDENT>", "def"]


@pytest.mark.parametrize("changed", [
    CODE.replace("2.0", "2.5"),
    CODE.replace("+ math.pi", "- math.pi"),
    CODE.replace('        """Its mass (kg)."""\n', '        label = "Its mass (kg)."\n'),  # a string kept
    # the same lines, another block structure: the return now outside the method (a dedent moved)
    CODE.replace("        return (2.0", "    return (2.0").replace("                + math", "            + math"),
])
def test_a_change_of_the_code_changes_the_tokens(changed):
    ast.parse(changed)
    assert code_tokens(changed) != code_tokens(CODE)


def test_an_f_string_is_one_token_its_source_on_every_python_version():
    """Python 3.12 tokenizes an f-string into parts (PEP 701), 3.11 as one string: both give its
    source, nested f-strings and format specs included; an f-string alone on a line is kept (it
    evaluates its fields), as is a plain string after it."""
    text = 'x = f"a{b!r:>{w}}c{f\'{d}\'}" + g(F"""e\n{h}""")  # a comment\nf"{x}" "s"\n'
    assert code_tokens(text) == ["x", "=", 'f"a{b!r:>{w}}c{f\'{d}\'}"', "+", "g", "(", 'F"""e\n{h}"""', ")",
                                 "<NEWLINE>", 'f"{x}"', '"s"', "<NEWLINE>", "<END>"]


def _imports(name: str) -> set[str]:
    """The core modules (paths in the core) the module ``name`` imports, where and how it does."""
    path = _CORE / name
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("biped_gait.core")):
            base = path.parents[node.level - 1] if node.level else _CORE.parent.parent
            target = base.joinpath(*(node.module or "").split("."))
            if target.with_suffix(".py").is_file():
                out.add(target.with_suffix(".py"))
            else:
                out |= {target / f"{alias.name}.py" for alias in node.names if (target / f"{alias.name}.py").is_file()}
        elif isinstance(node, ast.Import):
            for alias in node.names:
                assert not alias.name.startswith("biped_gait"), (name, alias.name)  # none so far: resolve them here if one comes
    return {str(p.relative_to(_CORE)) for p in out}


def test_the_fingerprints_hold_every_core_module_the_model_and_turning_code_import():
    for code in (MODEL_CODE, MODEL_CODE + TURNING_CODE):
        python = [name for name in code if name.endswith(".py")]
        missing = {(name, imported) for name in python for imported in _imports(name) if imported not in code}
        assert not missing, f"imported but not fingerprinted (add them to MODEL_CODE or TURNING_CODE): {sorted(missing)}"
    assert not set(MODEL_CODE) & set(TURNING_CODE)


def test_the_packages_the_fingerprinted_modules_live_in_hold_no_code():
    """Importing a module runs its packages' __init__.py: they hold docstrings only."""
    packages = {folder for name in MODEL_CODE + TURNING_CODE for folder in (_CORE / name).parents
                if _CORE.parent in folder.parents or folder == _CORE.parent}
    assert _CORE.parent.name == "biped_gait" and len(packages) >= 4
    for folder in packages:
        init = Path(folder) / "__init__.py"
        if init.is_file():
            assert code_tokens(init.read_text()) == ["<END>"], init
