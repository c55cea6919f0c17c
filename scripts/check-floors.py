#!/usr/bin/env python3
"""Checks that the code's floors only look down: a file of src/FLOOR includes headers of its own
floor and of the floors below it (cmake/floors.txt, bottom first), and apps/ and python/src
include no private header of src/; a public header that belongs to a floor (the Renderer's
<hsr/render.hpp>, the top floor's) is included by no file below it. Prints one line per upward include and exits 1 if any;
run by ctest (floors_check) and by hand: scripts/check-floors.py [REPO]."""
import pathlib
import re
import sys

repo = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
floors = [line.strip() for line in (repo / "cmake/floors.txt").read_text().splitlines()
          if line.strip() and not line.startswith("#")]
level = {name: i for i, name in enumerate(floors)}
include = re.compile(r'^\s*#\s*include\s+"([^"/]+)/[^"]+"', re.M)
sources = (".cpp", ".hpp", ".h")
problems = []

# Every folder of src/ is a floor of the list.
for folder in sorted(p for p in (repo / "src").iterdir() if p.is_dir()):
    if folder.name not in level:
        problems.append(f"src/{folder.name}/: a folder that is no floor of cmake/floors.txt")

for path in sorted((repo / "src").rglob("*")):
    if path.suffix not in sources or not path.is_file():
        continue
    own = path.relative_to(repo / "src").parts[0]
    if own not in level:
        continue
    for target in include.findall(path.read_text(errors="replace")):
        if target in level and level[target] > level[own]:
            problems.append(f"{path.relative_to(repo)}: includes {target}/ (floor {level[target]}), "
                            f"above its own {own}/ (floor {level[own]})")

# Public headers that declare what a floor implements and the floors below must not see
# (they read the render options from <hsr/options.hpp>).
owned = {"render.hpp": "render"}
public = re.compile(r'^\s*#\s*include\s+<hsr/([^>]+)>', re.M)
for path in sorted((repo / "src").rglob("*")):
    if path.suffix not in sources or not path.is_file():
        continue
    own = path.relative_to(repo / "src").parts[0]
    for header in public.findall(path.read_text(errors="replace")):
        floor = owned.get(header)
        if floor and own in level and level[own] < level[floor]:
            problems.append(f"{path.relative_to(repo)}: includes <hsr/{header}>, the {floor}/ floor's, "
                            f"above its own {own}/ (include <hsr/options.hpp> for RenderOptions)")
for path in sorted((repo / "include/hsr").glob("*.hpp")):
    if path.name in owned or path.name == "hsr.hpp":
        continue
    for header in public.findall(path.read_text(errors="replace")):
        if header in owned:
            problems.append(f"{path.relative_to(repo)}: includes <hsr/{header}>, which every floor below "
                            f"{owned[header]}/ would then see")

for top in ("apps", "python/src"):
    for path in sorted((repo / top).rglob("*")):
        if path.suffix in sources and path.is_file():
            for target in include.findall(path.read_text(errors="replace")):
                if target in level:
                    problems.append(f"{path.relative_to(repo)}: includes the private {target}/ of src/ "
                                    "(use the public headers, include/hsr/)")

for line in problems:
    print(line)
if problems:
    sys.exit(1)
print(f"floors: {' < '.join(floors)}: no include runs up a floor")
