#!/usr/bin/env python3
"""Checks that #include arrows point down the layers of docs/architecture.md.

Usage: tools/check_layers.py [SOURCE_DIR]      exit 1 and one line per wrong include
       tools/check_layers.py --self-test       plants wrong includes in a copy; exit 0
                                               only if each one is caught

Each source folder has a layer; a file may include project headers of its own
folder and of the folders its layer lists. Test files (*_test.cc) of the
geometry library may also include other domains of the library (test data
comes from io/ and synth/), never the engine, the stages or the CLI.
"""
import os
import re
import shutil
import sys
import tempfile

G = "stages/geometry/"
# folder -> folders it may include (besides itself).
ALLOWED = {
    "base/": [],
    G + "core/": ["base/"],
    G + "testing/": ["base/", G + "core/"],
    G + "io/": ["base/", G + "core/"],
    G + "points/": ["base/", G + "core/"],
    G + "synth/": ["base/", G + "core/"],
    G + "uv/": ["base/", G + "core/"],
    G + "metrics/": ["base/", G + "core/"],
    G + "mesh/": ["base/", G + "core/", G + "synth/", G + "points/"],
    G + "render/": ["base/", G + "core/", G + "synth/"],
    G + "bake/": ["base/", G + "core/", G + "synth/", G + "points/", G + "mesh/", G + "uv/"],
    "engine/": ["base/"],
    # Stage adapters: the engine's stage interface and the whole library.
    "stages/": ["base/", "engine/", G],
    "cli/": ["base/", "engine/", "stages/"],
}
# Where a folder is not listed, the longest listed prefix decides; folders
# outside every prefix (tests/, bench/, examples/) may include anything.
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def layer_of(path):
    best = None
    for folder in ALLOWED:
        if path.startswith(folder) and (best is None or len(folder) > len(best)):
            best = folder
    return best


def check(root):
    problems = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and not d.startswith("build")
                       and d != "node_modules"]
        for name in filenames:
            if not name.endswith((".h", ".cc", ".in")):
                continue
            full = os.path.join(dirpath, name)
            rel = os.path.relpath(full, root).replace(os.sep, "/")
            layer = layer_of(rel)
            if layer is None:
                continue
            allowed = [layer] + ALLOWED[layer]
            if name.endswith("_test.cc") and layer.startswith(G):
                allowed.append(G)
            with open(full, encoding="utf-8", errors="replace") as f:
                text = f.read()
            for match in INCLUDE.finditer(text):
                target = match.group(1)
                if "/" not in target:
                    continue  # a generated or same-folder header
                if not any(target.startswith(a) for a in allowed):
                    line = text.count("\n", 0, match.start()) + 1
                    problems.append(f"{rel}:{line}: includes {target}, which is not below "
                                    f"its layer {layer} (may include: {', '.join(allowed)})")
    return problems


def self_test(root):
    planted = [
        (G + "core/mesh.h", '#include "stages/geometry/mesh/decimate.h"\n'),
        (G + "io/ply.h", '#include "engine/stage.h"\n'),
        ("engine/cache.h", '#include "stages/params.h"\n'),
        ("base/status.h", '#include "engine/key.h"\n'),
        ("stages/params.h", '#include "cli/cli.h"\n'),
    ]
    failures = 0
    for path, line in planted:
        with tempfile.TemporaryDirectory() as tmp:
            for top in ("base", "engine", "stages", "cli"):
                shutil.copytree(os.path.join(root, top), os.path.join(tmp, top),
                                ignore=shutil.ignore_patterns("build*"))
            if check(tmp):
                print(f"self-test: the clean copy already has problems", file=sys.stderr)
                return 1
            with open(os.path.join(tmp, path), "a") as f:
                f.write(line)
            found = check(tmp)
            if not any(p.startswith(path + ":") for p in found):
                print(f"self-test: planted {line.strip()} in {path} was not caught", file=sys.stderr)
                failures += 1
    print(f"self-test: {len(planted) - failures} of {len(planted)} planted wrong includes caught")
    return 1 if failures else 0


def main():
    args = sys.argv[1:]
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if args and args[0] == "--self-test":
        return self_test(args[1] if len(args) > 1 else here)
    root = args[0] if args else here
    problems = check(root)
    for p in problems:
        print(p)
    print(f"check_layers: {len(problems)} includes against the layers")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
