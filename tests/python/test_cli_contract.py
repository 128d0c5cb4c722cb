"""The scripted run's contract (examples/run_estimate.py): its docstring
documents every flag the CLI accepts, and the CLI offers the choices the
estimate declares."""
import os

from sunlapse import cli
from sunlapse.estimate import options

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def flags():
    return [s for a in cli.build_parser()._actions for s in a.option_strings
            if s.startswith("--") and s != "--help"]


def test_the_contract_documents_every_flag():
    import ast
    doc = ast.get_docstring(ast.parse(open(os.path.join(ROOT, "examples", "run_estimate.py"))
                                      .read()))
    missing = [f for f in flags() if f not in doc]
    assert not missing, f"examples/run_estimate.py does not document {missing}"
    assert "--times" in flags() and "--fixed-latitude" in flags()  # the check sees them
    assert "--fit-latitude" in flags()


def test_the_cli_offers_the_estimates_choices():
    p = cli.build_parser()
    choice = {a.dest: list(a.choices) for a in p._actions if a.choices}
    assert choice["method"] == options.keys(options.METHODS)
    assert choice["smoothing"] == options.keys(options.SMOOTHINGS)
