"""The Python functions against the command line: every option of ``hbid identify``,
``simulate``, ``embed`` and ``upos`` is a keyword of the function of the same name, spelled with
``_`` for ``-``, with the same default; and the extension's type stubs (``_hbid.pyi``) are its
signatures.

The command line's options are read from ``cli_options.json``, which a Rust test writes from
the command line's own definition (and fails when it is stale)."""

from __future__ import annotations

import ast
import inspect
import json
import math
import pathlib

import pytest

import hbid
from hbid import _hbid

HERE = pathlib.Path(__file__).resolve().parent
CLI = json.loads((HERE / "cli_options.json").read_text())

#: Options that only change how the command line shows its result, not what is computed.
DISPLAY_ONLY = {"json", "quiet", "timings"}

#: Python keywords without an option: where the command line names a file (its positional
#: argument and columns), Python also takes arrays; ``compare``'s model is the command line's
#: first positional argument.
ARRAYS = {"x", "t", "drive", "model"}

#: Options that write a figure: the command line draws it, Python returns the arrays
#: (``Comparison.runs``) for a figure of one's own.
FIGURES = {"plot"}

#: Old names the command line keeps as aliases (``--forcing-col``), which Python takes as old
#: keywords (with a DeprecationWarning), mapped to the new ones.
from hbid._common import RECORD_RENAMED  # noqa: E402
from hbid._simulate import SIMULATE_RENAMED  # noqa: E402

RENAMED_BY_COMMAND = {
    "identify": RECORD_RENAMED,
    "embed": RECORD_RENAMED,
    "upos": RECORD_RENAMED,
    "simulate": SIMULATE_RENAMED,
    "compare": {},
}


def _same_default(cli: dict, py) -> bool:
    """Whether a Python default is the command line's."""
    if cli["flag"]:
        return py is False
    text = cli["default"]
    if text is None:
        return py is None
    if isinstance(py, bool) or py is None:
        return False
    if isinstance(py, (int, float)):
        try:
            return math.isclose(float(text), float(py), rel_tol=0.0, abs_tol=0.0)
        except ValueError:
            return False
    return str(py) == text


@pytest.mark.parametrize("command", sorted(CLI))
def test_every_option_is_a_keyword_with_the_same_default(command):
    function = getattr(hbid, command)
    parameters = inspect.signature(function).parameters
    keywords = {
        name: p for name, p in parameters.items() if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)
    }
    options = {name: o for name, o in CLI[command].items() if name not in DISPLAY_ONLY | FIGURES}
    missing = sorted(set(options) - set(keywords))
    assert not missing, f"hbid.{command} lacks {missing}"
    extra = sorted(set(keywords) - set(options) - ARRAYS)
    assert not extra, f"hbid.{command} has keywords the command line does not: {extra}"
    for name, option in options.items():
        default = keywords[name].default
        assert _same_default(option, default), (
            f"hbid.{command}({name}={default!r}) but the command line's default is "
            f"{'off' if option['flag'] else option['default']}"
        )


@pytest.mark.parametrize("command", sorted(CLI))
def test_old_names_are_the_command_lines_aliases(command):
    aliases = {a: name for name, o in CLI[command].items() for a in o["aliases"]}
    assert aliases == dict(RENAMED_BY_COMMAND[command])


def _stub_functions() -> dict:
    tree = ast.parse((pathlib.Path(hbid.__file__).parent / "_hbid.pyi").read_text())
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}


def test_the_stubs_are_the_extensions_signatures():
    stubs = _stub_functions()
    public = {name for name in dir(_hbid) if not name.startswith("_") and callable(getattr(_hbid, name))}
    assert set(stubs) == public
    for name, node in stubs.items():
        actual = inspect.signature(getattr(_hbid, name))
        args = node.args
        stubbed = [a.arg for a in args.posonlyargs + args.args] + [a.arg for a in args.kwonlyargs]
        assert stubbed == list(actual.parameters), name
        kw_defaults = {
            a.arg: ast.literal_eval(d) for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None
        }
        positional = args.posonlyargs + args.args
        for a, d in zip(positional[len(positional) - len(args.defaults) :], args.defaults):
            kw_defaults[a.arg] = ast.literal_eval(d)
        for p in actual.parameters.values():
            if p.default is not p.empty:
                assert kw_defaults.get(p.name, "missing") == p.default, f"{name}({p.name})"
            else:
                assert p.name not in kw_defaults, f"{name}({p.name}) has no default"


@pytest.mark.parametrize("command", sorted(CLI))
def test_docs_python_md_documents_every_keyword(command):
    docs = (HERE.parents[1] / "docs" / "python.md").read_text()
    parameters = inspect.signature(getattr(hbid, command)).parameters
    missing = [
        name
        for name, p in parameters.items()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and name != "x" and f"`{name}`" not in docs
    ]
    assert not missing, f"docs/python.md does not document hbid.{command}'s {missing}"


def test_the_model_methods_take_the_command_lines_tolerance():
    """``Model.simulate`` has no command of its own: its ``rtol`` is ``hbid simulate``'s default,
    which the extension publishes once (``DEFAULT_RTOL``) for every signature that has one."""
    cli = CLI["simulate"]["rtol"]
    assert _same_default(cli, _hbid.DEFAULT_RTOL)
    assert inspect.signature(hbid.Model.simulate).parameters["rtol"].default == _hbid.DEFAULT_RTOL
