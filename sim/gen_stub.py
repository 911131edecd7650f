"""Rewrite the generated RenderParams section of sim/_core.pyi from params.def:
`python -m sim.gen_stub`. tests/test_params.py fails when it is stale."""
import sys

from .params import STUB_PATH, stub_text


def main() -> int:
    text = STUB_PATH.read_text()
    new = stub_text(text)
    if new != text:
        STUB_PATH.write_text(new)
        print(f"wrote {STUB_PATH}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
