#!/usr/bin/env python3
"""gen_map.py HEADER MAP - the linker version script of libsagitta: the
functions the public header marks SG_API, and nothing else.  A wildcard
such as sg_* would also export what a public name becomes in the
per-instruction-set builds (sg_opd_of_rays_v4 and the like)."""
import re
import sys

text = open(sys.argv[1]).read()
names = sorted(set(re.findall(r'^SG_API[^;{]*?\b(sg_\w+)\s*\(', text, re.M)))
with open(sys.argv[2], "w") as f:
    f.write("/* Made by src/gen_map.py from sagitta.h: the public API. */\n")
    f.write("SAGITTA_0 {\n  global:\n")
    for n in names:
        f.write("    %s;\n" % n)
    f.write("  local:\n    *;\n};\n")
