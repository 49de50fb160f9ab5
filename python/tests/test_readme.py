"""The README's Python example runs as printed (on the embedded synthetic default) and tracks the room."""
import contextlib
import io
import pathlib
import re

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def test_readme_example_runs():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert len(blocks) == 1, "README.md should hold one Python example"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(blocks[0], "README.md", "exec"), {})
    state, faces, _, _, ate, _ = out.getvalue().split()
    # 30 noisy synthetic frames at 1 cm voxels: tracked throughout, a dense mesh, ATE of a few millimetres
    assert state == "tracked" and int(faces) > 10000 and float(ate) < 0.01
