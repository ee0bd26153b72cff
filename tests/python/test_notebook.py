"""examples/python/convergence.ipynb is stored without outputs (the test python.notebook executes
it; a committed notebook with outputs would make every re-run a large diff of embedded PNGs)."""

import json
import os
from pathlib import Path

SOURCE_DIR = Path(os.environ.get("RKHS_STUDY_SOURCE_DIR", Path(__file__).parents[2]))
NOTEBOOK = SOURCE_DIR / "examples" / "python" / "convergence.ipynb"


def test_the_example_notebook_is_stored_without_outputs():
    notebook = json.loads(NOTEBOOK.read_text())
    code = [cell for cell in notebook["cells"] if cell["cell_type"] == "code"]
    assert code
    for number, cell in enumerate(code, 1):
        assert cell.get("outputs") == [], f"code cell {number} has outputs: clear them"
        assert cell.get("execution_count") is None, f"code cell {number} has an execution count"
    assert notebook["metadata"]["kernelspec"]["name"] == "python3"
