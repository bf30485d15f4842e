"""An exported revision's ``sim/`` and ``checker/`` made importable as ``cablecheck``, for the benchmarks' ``--before``.

The move of 2026-11-28 (2fd24d5, 38e6334) turned the folder ``sim/`` into
the package ``cablecheck`` (its flat modules went into stage packages:
``sim/run.py`` is ``cablecheck.run.runner``, ``sim/build.py``
``cablecheck.build.stages``) and ``checker/`` into ``cablecheck.checker``,
and removed the re-export facades (``sim/scene/__init__.py``,
``sim/record/__init__.py``, ``sim/build.py``). The benchmarks that compare
this checkout with older revisions (``bench_record.py``, ``bench_scale.py``)
run a child Python on the revision's ``sim/`` and ``checker/``, exported by
``git archive`` to a temporary folder and put on ``PYTHONPATH``, and that
child uses today's names. :func:`export` makes such a folder answer to them:

- a revision from after the move (``sim/run/`` is a package) gets a folder
  ``cablecheck`` (a symbolic link to ``sim``) and ``sim/checker`` (a link to
  ``../checker``): the layout the installed package has;
- a revision from before it is first rewritten into the new layout with the
  move's own table (:data:`FLAT`, the one its one-off tool used): each flat
  module of ``sim/`` goes to its stage package, and every import, dotted
  name and ``sim/x.py`` path in the code, its strings and comments is
  rewritten to the new names; a name imported from a facade (``from
  sim.scene import Scene``) is imported from the module the facade took it
  from, as the move did. A module the table does not name (one that existed
  only in older revisions, such as the single-file ``sim/record.py``) keeps
  its name under the package (``cablecheck.record``), and becomes the
  package's ``__init__`` when a stage package took that name (the
  single-file ``sim/scene.py`` beside ``meshfile``, which went to
  ``cablecheck.scene.meshfile``). A module in the table that the revision
  does not have is simply absent.

Both get a ``sitecustomize.py`` that drops the editable install's finder
from ``sys.meta_path`` in the child: that finder maps ``cablecheck`` and its
immediate sub-modules to this checkout's ``sim/``, so a module the revision
lacks would otherwise load silently from today's code instead of failing.
:func:`check` imports modules from the folder in a fresh interpreter and
fails unless each one's file lies in it.

What it does not do: it makes the old code answer to the new *module*
names only. A module today's code names that the revision did not have
(``cablecheck.record.recorder`` where ``record`` was one file), a name that
moved between modules after the revision, a command-line option or scene
key the revision lacks are not bridged: the benchmark's child code has to
ask for what the revision had. It does not fix the
revisions 2fd24d5 and 38e6334, whose ``sim/build/`` was never committed (a
module of it then fails to import). It reads no git history beyond the one
``git archive``, and changes nothing outside the exported folder.
"""

from __future__ import annotations

import ast
import io
import json
import os
import re
import subprocess
import sys
import tempfile
import tokenize
from pathlib import Path

FLAT = {
    'build': 'build.stages', 'built': 'build.built', 'cablephysics': 'build.cablephysics',
    'cableplan': 'build.cableplan', 'route': 'build.route', 'routecheck': 'build.routecheck',
    'obstacles': 'build.obstacles', 'mjspec': 'build.mjspec', 'modelread': 'build.modelread',
    'contactbits': 'build.contactbits', 'startframes': 'build.startframes', 'staticbuild': 'build.static',
    'substeps': 'build.substeps', 'checkview': 'build.checkview', 'meshfile': 'scene.meshfile',
    'detector': 'detection.detector', 'detection_mesh': 'detection.mesh', 'surfacereach': 'detection.surfacereach',
    'contacts': 'detection.contacts', 'hullgap': 'detection.hullgap',
    'run': 'run.runner', 'loop': 'run.loop', 'kinematic': 'run.kinematic', 'ahead': 'run.ahead',
    'stepcheck': 'run.stepcheck', 'divergence': 'run.divergence', 'mjlog': 'run.mjlog', 'stop': 'run.stop',
    'motion': 'run.motion', 'curves': 'run.curves', 'jointspace': 'run.jointspace', 'sweep': 'run.sweep',
    'report': 'report.document', 'baseline': 'report.baseline', 'review': 'report.review',
    'outputs': 'report.outputs',
    'study': 'study.definition', 'studycluster': 'study.cluster', 'studygoal': 'study.goal',
    'studyplot': 'study.plot', 'studyresult': 'study.result', 'studyrun': 'study.execute',
    'studysearch': 'study.search', 'bundle': 'study.bundle',
    'bench': 'bench.command', 'benchcheck': 'bench.checker_tables', 'benchfcl': 'bench.fcl',
    'benchplot': 'bench.plot', 'benchscene': 'bench.scenes', 'benchsim': 'bench.sim_tables',
    'benchtable': 'bench.table', 'harness': 'bench.harness', 'reference': 'bench.reference',
    'validation': 'bench.physics_cases',
    'cli': 'cli.main', 'cliargs': 'cli.args', 'cliprint': 'cli.printing',
}
"""The move's table (2fd24d5): flat module of ``sim/`` -> its module under ``cablecheck``."""

FACADES = ("scene", "record", "build")
"""The modules of ``sim/`` that re-exported names before the move; an import of such a name is
rewritten to the module it came from (the move did the same)."""

ROOTS = ("sim", "checker")

_SITECUSTOMIZE = '''"""Written by benchmarks/relayout.py: `cablecheck` comes from this folder only.

The editable install's finder maps `cablecheck` and its immediate sub-modules to the
checkout it was installed from; dropped here, a module this revision lacks fails to
import instead of loading from that checkout.
"""
import sys

sys.meta_path[:] = [f for f in sys.meta_path
                    if not (getattr(f, "__module__", "") or "").startswith("__editable___cablecheck")]
'''


def is_new_layout(tree: Path) -> bool:
    """Whether the exported ``sim/`` is already laid out as after the move (``sim/run/`` a package)."""
    return (tree / "sim" / "run" / "__init__.py").is_file()


def export(repo: Path, rev: str, prefix: str = "relayout_") -> Path:
    """``sim/`` and ``checker/`` of git revision ``rev`` of ``repo`` in a new temporary folder, importable
    as ``cablecheck`` from ``PYTHONPATH`` = that folder (see the module docstring); checked by :func:`check`."""
    folder = Path(tempfile.mkdtemp(prefix=prefix))
    archive = subprocess.run(["git", "-C", str(repo), "archive", rev, "checker", "sim"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    relayout(folder)
    check(folder)
    return folder


def relayout(tree: Path) -> bool:
    """Make the exported ``tree`` (holding ``sim/`` and ``checker/``) importable as ``cablecheck``; an old
    layout is rewritten first. Returns whether it was rewritten."""
    tree = Path(tree)
    old = not is_new_layout(tree)
    if old:
        _Rewrite(tree).apply()
    link = tree / "cablecheck"
    if not link.exists():
        link.symlink_to("sim", target_is_directory=True)
    inner = tree / "sim" / "checker"
    if not inner.exists():
        inner.symlink_to(Path("..") / "checker", target_is_directory=True)
    (tree / "sitecustomize.py").write_text(_SITECUSTOMIZE)
    return old


def check(tree: Path, modules: tuple[str, ...] = ("cablecheck", "cablecheck.checker")) -> dict[str, str]:
    """Import ``modules`` in a fresh interpreter with ``PYTHONPATH`` = ``tree`` (as the benchmarks' children
    do); their files, each of which must lie in ``tree`` (else RuntimeError)."""
    tree = Path(tree).resolve()
    code = ("import importlib, json, sys\n"
            f"print(json.dumps({{m: importlib.import_module(m).__file__ for m in {list(modules)!r}}}))")
    proc = subprocess.run([sys.executable, "-P", "-c", code], cwd=tree, capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(tree)), check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{tree}: {(proc.stderr.strip().splitlines() or ['?'])[-1]}")
    files = json.loads(proc.stdout.strip().splitlines()[-1])
    outside = {m: f for m, f in files.items() if not Path(f).resolve().is_relative_to(tree)}
    if outside:
        raise RuntimeError(f"{tree}: imported from outside it: {outside}")
    return files


class _Rewrite:
    """The move applied to one exported tree of the old layout (the one-off tool of 2fd24d5, on a plain
    folder instead of a git checkout)."""

    def __init__(self, tree: Path):
        self.tree = tree
        self.mod = {"sim": "cablecheck", "checker": "cablecheck.checker"}   # old dotted name -> new
        self.files: dict[Path, Path] = {}                                    # old file -> new file
        sim = tree / "sim"
        flat = sorted(p for p in sim.glob("*.py") if p.stem != "__init__")
        stages = {FLAT[p.stem].split(".")[0] for p in flat if p.stem in FLAT}
        for p in self._sources():
            parts = p.relative_to(tree).with_suffix("").parts
            old = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            if parts[0] == "checker":
                self.mod[old] = "cablecheck." + old
            elif p in flat:
                new = FLAT.get(p.stem, p.stem)
                self.mod[old] = "cablecheck." + new
                # a kept name a stage package also took: that package's __init__
                rel = Path(new, "__init__.py") if new in stages else Path(*new.split(".")).with_suffix(".py")
                self.files[p] = sim / rel
            elif old != "sim":
                self.mod[old] = "cablecheck." + old[len("sim."):]
        self.stages = stages
        self.reexport: dict[str, dict[str, tuple[str, str]]] = {}
        for name in FACADES:
            path = next((q for q in (sim / name / "__init__.py", sim / f"{name}.py") if q.is_file()), None)
            if path is None:
                continue
            table = {}
            for n in ast.parse(path.read_text()).body:
                if isinstance(n, ast.ImportFrom) and n.level == 0 and n.module and n.module.split(".")[0] in ROOTS:
                    for a in n.names:
                        table[a.asname or a.name] = (n.module, a.name)
            self.reexport["sim." + name] = table

    def _sources(self) -> list[Path]:
        return sorted(p for root in ROOTS for p in (self.tree / root).rglob("*.py") if "__pycache__" not in p.parts)

    def apply(self) -> None:
        for p in self._sources():
            src = p.read_text()
            new = self.rewrite_py(self.rewrite_imports(src), self.bound_roots(src))
            if p in self.files:       # one folder deeper: the repository is one parent further
                new = re.sub(r"(__file__\)(?:\.resolve\(\))?\.parents\[)(\d+)\]",
                             lambda m: f"{m.group(1)}{int(m.group(2)) + 1}]", new)
            if new != src:
                p.write_text(new)
        for old, new in self.files.items():
            new.parent.mkdir(exist_ok=True)
            old.rename(new)
        for stage in self.stages:
            init = self.tree / "sim" / stage / "__init__.py"
            if not init.exists():
                init.write_text(f'"""cablecheck.{stage}: modules of an old revision, laid out by '
                                f'benchmarks/relayout.py."""\n')

    # -- names ------------------------------------------------------------------------

    def new_name(self, old: str, minparts: int = 1) -> str | None:
        parts = old.split(".")
        for k in range(len(parts), minparts - 1, -1):
            pre = ".".join(parts[:k])
            if pre in self.mod:
                return self.mod[pre] + "".join("." + x for x in parts[k:])
        return None

    def resolve(self, mod: str, name: str) -> tuple[str, str]:
        """Where a name imported from a facade was defined: follow its re-exports."""
        seen = 0
        while mod in self.reexport and name in self.reexport[mod] and seen < 10:
            mod, name = self.reexport[mod][name]
            seen += 1
        return mod, name

    # -- imports ------------------------------------------------------------------------

    def rewrite_imports(self, src: str) -> str:
        """Every ``import sim.x`` / ``from sim.x import y`` (and ``checker``) under the new names."""
        tree = ast.parse(src)
        data = src.encode()
        lines = re.split(rb"(?<=\n)", data)
        offs = [0]
        for line in lines:
            offs.append(offs[-1] + len(line))
        edits = []
        for node in ast.walk(tree):
            if (isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                    and node.module.split(".")[0] in ROOTS):
                groups: dict[str, list[tuple[str, str | None]]] = {}
                for a in node.names:
                    m, n = node.module, a.name
                    if f"{m}.{n}" in self.mod:                     # a module: from sim import run
                        nm, _, n = self.mod[f"{m}.{n}"].rpartition(".")
                    else:
                        m, n = self.resolve(m, n)
                        nm = self.new_name(m)
                    asname = a.asname or (a.name if n != a.name else None)
                    groups.setdefault(nm, []).append((n, asname))
                # '; ' keeps one logical line: valid wherever the import stood
                text = "; ".join(f"from {m} import " + ", ".join(n if a is None or a == n else f"{n} as {a}"
                                                                  for n, a in ns)
                                 for m, ns in groups.items())
                edits.append((node, text))
            elif isinstance(node, ast.Import) and any(a.name.split(".")[0] in ROOTS for a in node.names):
                items = [(self.new_name(a.name) if a.name.split(".")[0] in ROOTS else a.name)
                         + (f" as {a.asname}" if a.asname else "") for a in node.names]
                edits.append((node, "import " + ", ".join(items)))
        for node, text in sorted(edits, key=lambda e: (e[0].lineno, e[0].col_offset), reverse=True):
            a = offs[node.lineno - 1] + node.col_offset           # ast's columns count UTF-8 bytes
            b = offs[node.end_lineno - 1] + node.end_col_offset
            data = data[:a] + text.encode() + data[b:]
        return data.decode()

    # -- dotted names, strings, comments ----------------------------------------------------

    _DOTTED = re.compile(r"(?<![\w./\-])((?:sim|checker)(?:\.[A-Za-z_]\w*)+)")
    _PATHS = re.compile(r"(?<![\w./\-])sim/(\w+(?:/\w+)*)\.py")

    def rewrite_text(self, src: str) -> str:
        """Known module names (``sim.run.X``) and file paths (``sim/run.py``) in text, under the new names."""
        def dotted(m):
            return self.new_name(m.group(1), minparts=2) or m.group(1)

        def path(m):
            p = self.tree / "sim" / (m.group(1) + ".py")
            return str(self.files[p].relative_to(self.tree)) if p in self.files else m.group(0)

        return self._PATHS.sub(path, self._DOTTED.sub(dotted, src))

    @staticmethod
    def bound_roots(src: str) -> set[str]:
        """``sim`` / ``checker`` when a plain ``import sim.x`` binds them as names in the module."""
        roots = set()
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname is None and a.name.split(".")[0] in ROOTS:
                        roots.add(a.name.split(".")[0])
        return roots

    def rewrite_py(self, src: str, roots: set[str]) -> str:
        """Strings and comments through :meth:`rewrite_text`; dotted uses of a bound root (``sim.run.X``
        after ``import sim.run``) under the new names."""
        lines = re.split("(?<=\n)", src)
        offs = [0]
        for line in lines:
            offs.append(offs[-1] + len(line))
        toks = list(tokenize.generate_tokens(io.StringIO(src).readline))
        edits = []
        i = 0
        while i < len(toks):
            t = toks[i]
            if t.type in (tokenize.STRING, tokenize.COMMENT):
                new = self.rewrite_text(t.string)
                if new != t.string:
                    edits.append((offs[t.start[0] - 1] + t.start[1], offs[t.end[0] - 1] + t.end[1], new))
            elif t.type == tokenize.NAME and t.string in roots and not (i > 0 and toks[i - 1].string == "."):
                j, chain = i, [t.string]
                while j + 2 < len(toks) and toks[j + 1].string == "." and toks[j + 2].type == tokenize.NAME:
                    chain.append(toks[j + 2].string)
                    j += 2
                text = ".".join(chain)
                new = self.rewrite_text(text)
                if new != text:
                    edits.append((offs[t.start[0] - 1] + t.start[1], offs[toks[j].end[0] - 1] + toks[j].end[1], new))
                i = j
            i += 1
        for a, b, new in sorted(edits, reverse=True):
            src = src[:a] + new + src[b:]
        return src


if __name__ == "__main__":
    # python benchmarks/relayout.py REV: export and lay out one revision, print its folder
    print(export(Path(__file__).resolve().parents[1], sys.argv[1]))
