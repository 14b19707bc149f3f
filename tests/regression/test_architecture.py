# SPDX-License-Identifier: BSD-3-Clause
"""doc/architecture.md against the tree:
- the layers of its first table are those of CMakeLists.txt (DEM_LAYERS, in that order), each
  in the folder it names;
- every module it names in a layer's list is a source file of that layer's folder, holding
  that module (one module per file, named after it), and every source file of src/ and io/
  is named there;
- every `use` of a project module in a source file is of its own layer or one below (what
  the build enforces with a module folder per layer, checked here from the sources);
- its table of the folders of the tree names every folder at the top of the tracked tree
  (git ls-files; skipped outside a git checkout) and only folders that exist.
usage: test_architecture.py DEM WORKDIR (neither is used: the test reads the tree)"""
import glob
import os
import re

from regression_util import ROOT, check, finish

with open(os.path.join(ROOT, "doc", "architecture.md")) as f:
    page = f.read()
with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
    cmake_layers = re.search(r"set\(DEM_LAYERS ([^)]*)\)", f.read()).group(1).split()

# the first table: | layer | `folder` | ... |
layer_rows = re.findall(r"^\| (\w+) \| `([^`]+)` \|", page, re.M)
layers = [name for name, _ in layer_rows]
folder_of = dict(layer_rows)
check(layers[:len(cmake_layers)] == cmake_layers and layers[len(cmake_layers):] == ["app"],
      f"the page's layers {layers} are CMake's {cmake_layers} and then app")

# the lists of modules: a line "**layer** (`folder`)" and the `dem...` names after it, up to
# the next such line or heading
named = {}
for m in re.finditer(r"^\*\*(\w+)\*\* \(`([^`]+)`\)(.*?)(?=^\*\*\w+\*\* \(|^#)", page,
                     re.M | re.S):
    layer, folder, text = m.groups()
    check(folder_of.get(layer) == folder, f"the list of {layer} is of its folder {folder}")
    for module in re.findall(r"(?:^\| |^|: |, )`(dem\w*)`", text, re.M):
        named[module] = layer

sources = sorted(glob.glob(os.path.join(ROOT, "src", "*", "*.[fF]90"))
                 + glob.glob(os.path.join(ROOT, "io", "*.[fF]90")))
layer_of_file = {}
for path in sources:
    folder = os.path.relpath(os.path.dirname(path), ROOT)
    layer = {v: k for k, v in folder_of.items()}.get(folder)
    check(layer is not None, f"{folder} is the folder of a layer of the page")
    stem = os.path.splitext(os.path.basename(path))[0]
    layer_of_file[stem] = layer
    check(named.get(stem) == layer, f"{os.path.relpath(path, ROOT)} is named in the list of "
          f"its layer {layer} (named in: {named.get(stem)})")
    with open(path) as f:
        text = f.read()
    units = re.findall(r"^\s*(?:module|program)\s+(\w+)\s*$", text, re.M | re.I)
    check(units == [stem], f"{os.path.relpath(path, ROOT)} holds the one unit {stem}: {units}")
for module, layer in named.items():
    check(module in layer_of_file, f"the page names {module} ({layer}), which is no source "
          "file")

rank = {name: k for k, name in enumerate(layers)}
for path in sources:
    stem = os.path.splitext(os.path.basename(path))[0]
    with open(path) as f:
        used = set(re.findall(r"^\s*use\s+(dem\w*)", f.read(), re.M | re.I))
    for module in sorted(used - {stem}):
        if module not in layer_of_file:
            check(False, f"{stem} uses {module}, which is no module of the tree")
            continue
        check(rank[layer_of_file[module]] <= rank[layer_of_file[stem]],
              f"{stem} ({layer_of_file[stem]}) uses {module} ({layer_of_file[module]}), a "
              "higher layer")
# the folders of the tree: | `folder` | what | rows after the heading
section = page.split("## The folders of the tree", 1)
check(len(section) == 2, "the page has a section The folders of the tree")
tree_rows = re.findall(r"^\| `([^`/]+)` \|", section[-1].split("\n## ", 1)[0], re.M)
for folder in tree_rows:
    check(os.path.isdir(os.path.join(ROOT, folder)), f"the folder {folder} of the page exists")
try:
    import subprocess
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.split("\n")
except (OSError, subprocess.CalledProcessError):
    tracked = []
    print("not a git checkout: the top-level folders are not checked")
top = sorted({t.split("/")[0] for t in tracked if "/" in t})
for folder in top:
    check(folder in tree_rows, f"the top-level folder {folder} is in the page's table of the "
          "folders of the tree (doc/architecture.md)")

print(f"{len(sources)} source files, {len(named)} modules named, {len(layers)} layers")
finish()
