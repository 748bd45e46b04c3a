"""Give an installed Bosun the kernels this checkout's set-up compiled (scripts/core_job.sh --prepare).

numba caches a kernel's machine code in ``__pycache__`` beside its source file, valid while that file's
content is the same (numba 0.68 hashes it; the code, the signature and the CPU are part of each entry's key).  For every
installed source file that is byte for byte this checkout's and has a cache here, the cache files are copied
beside the installed file: the same code for the same machine, loaded in
about a second instead of compiled again (93 s on one core of the 2-core VM, beside the main suite: issue 28,
item 5).  A file that differs, or a checkout without a cache, is left alone: it compiles as at a user's first
start.

Usage: python scripts/seed_kernel_cache.py CHECKOUT   (with the installed environment's python)
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path


def seed(checkout: Path, installed: Path) -> int:
    """Cache files copied from ``checkout``'s package folder into ``installed``'s."""
    copied = 0
    for src in sorted(checkout.rglob("*.py")):
        # numba's index and data, and Bosun's stamp of the kernel modules a file imports (app/models/kernels.py
        # clears a cache without it: numba does not follow a kernel's calls into another module)
        pattern = f"__pycache__/{src.stem}.*"
        cache = sorted(f for f in src.parent.glob(pattern) if f.suffix in (".nbi", ".nbc", ".sha256"))
        dst = installed / src.relative_to(checkout)
        if not cache or not dst.is_file() or dst.read_bytes() != src.read_bytes():
            continue
        (dst.parent / "__pycache__").mkdir(exist_ok=True)
        for f in cache:
            shutil.copy2(f, dst.parent / "__pycache__" / f.name)
            copied += 1
    return copied


if __name__ == "__main__":
    import app

    n = seed(Path(sys.argv[1]).resolve() / "app", Path(app.__file__).parent)
    print(f"core job: {n} kernel cache files taken from the checkout's set-up")
