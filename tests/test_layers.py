#!/usr/bin/env python3
"""test_layers.py - the engine's subsystems include each other in layers.

src/ is one directory a subsystem (docs/ARCHITECTURE.md).  Fails, naming
the file and line, when
  - a file includes another directory's private header (D/D_int.h);
  - a file includes a header of another directory that is not its
    interface (D/D.h), but for the arithmetic headers of num/ and the
    shapes' vector forms (shape_vd.h, shape_vdd.h), which the trace's
    vector kernels compile once per instruction set;
  - the directories' includes form a cycle (named by its directories and
    one include of each step);
  - a file of ui/ includes an engine header other than sagitta.h.
Headers are found as the compiler finds them: beside the including file,
then in src/ and its directories (src/meson.build's include path).

    test_layers.py [SRC_ROOT]   (default: the tree this file is in)
"""
import os
import re
import sys

# Headers of a directory other than its interface that other directories
# may include, and why.
SHARED = {
    'num/dd.h': 'double-double arithmetic',
    'num/vdd.h': 'double-double on vector lanes',
    'num/isa.h': 'the per-instruction-set names, included first',
    'shape/shape_vd.h': "the shapes' double kernels on lanes",
    'shape/shape_vdd.h': "the shapes' double-double kernels on lanes",
}

INC = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def includes(path):
    with open(path, encoding='utf-8') as f:
        text = f.read()
    for m in INC.finditer(text):
        yield text.count('\n', 0, m.start()) + 1, m.group(1)


def check(root):
    src = os.path.join(root, 'src')
    dirs = sorted(d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d)))
    where = {}  # header name -> its path under src/
    for d in [''] + dirs:
        for f in os.listdir(os.path.join(src, d)):
            if f.endswith('.h'):
                if f in where:
                    return ['src/%s and src/%s: two headers of one name on one include path'
                            % (where[f], os.path.join(d, f))]
                where[f] = os.path.join(d, f) if d else f
    errors = []
    edges = {}  # (from dir, to dir) -> first 'file:line includes header'
    for d in dirs:
        for f in sorted(os.listdir(os.path.join(src, d))):
            if not f.endswith(('.c', '.h')):
                continue
            rel = d + '/' + f
            for line, name in includes(os.path.join(src, d, f)):
                if os.path.exists(os.path.join(src, d, name)):
                    target = d + '/' + name
                elif name in where:
                    target = where[name]
                else:
                    continue  # the build's own (sg_config.h)
                if '/' not in target:
                    continue  # sagitta.h, the public header
                td, th = target.split('/', 1)
                if td == d:
                    continue
                at = 'src/%s:%d includes %s' % (rel, line, target)
                if th == td + '_int.h':
                    errors.append(at + ': the private header of ' + td + '/')
                elif th != td + '.h' and target not in SHARED:
                    errors.append(at + ': not the interface of ' + td + '/ (' + td + '/' + td + '.h)')
                edges.setdefault((d, td), at)
    # A cycle among the directories, by depth-first search.
    graph = {d: sorted(t for (f, t) in edges if f == d) for d in dirs}
    state = {}

    def visit(d, path):
        state[d] = 1
        for t in graph[d]:
            if state.get(t) == 1:
                cyc = path[path.index(t):] + [t]
                errors.append('include cycle between directories: ' + ' -> '.join(cyc) + '; ' +
                              '; '.join(edges[(a, b)] for a, b in zip(cyc, cyc[1:])))
            elif t not in state:
                visit(t, path + [t])
        state[d] = 2

    for d in dirs:
        if d not in state:
            visit(d, [d])
    # The program sees the engine through its public header alone.
    for base, _, files in os.walk(os.path.join(root, 'ui')):
        for f in sorted(files):
            if f.endswith(('.c', '.h')):
                p = os.path.join(base, f)
                for line, name in includes(p):
                    if name in where and name != 'sagitta.h' and \
                            not os.path.exists(os.path.join(base, name)):
                        errors.append('%s:%d includes the engine\'s %s' %
                                      (os.path.relpath(p, root), line, where[name]))
    return errors


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else \
        os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    errors = check(root)
    for e in errors:
        print(e)
    if errors:
        print('%d layering error%s' % (len(errors), '' if len(errors) == 1 else 's'))
        return 1
    print('src/: no include cycle between directories, no private header included from another')
    return 0


if __name__ == '__main__':
    sys.exit(main())
