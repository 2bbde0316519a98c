"""One iteration of a hot loop, as executed: a gdb script (see benches/README.md, "A model of
the two roll-out loops").

    FUNC=<hex offset of the function in the binary> OUT=<file> \
        gdb -q -batch -x trace_loop.py --args <binary> <arguments>

Stops at the function's third entry, then single-steps (stepping over calls) for MAXN
instructions (default 1500) and writes the instructions between the last two visits of the last
recorded address: one iteration of the loop the function was in, on the path it took, one
`offset<TAB>instruction` line each (AT&T syntax).
"""
import os

import gdb

func = int(os.environ["FUNC"], 16)
out = os.environ["OUT"]
maxn = int(os.environ.get("MAXN", "1500"))
gdb.execute("set pagination off")
gdb.execute("set disassembly-flavor att")
gdb.execute("starti")
name = os.path.basename(gdb.current_progspace().filename)
base = None
for line in gdb.execute("info proc mappings", to_string=True).splitlines():
    fields = line.split()
    if len(fields) >= 5 and fields[-1].endswith(name):
        base = int(fields[0], 16)
        break
if base is None:
    raise gdb.GdbError(f"no mapping of {name}")
gdb.execute(f"break *{base + func:#x}")
gdb.execute("ignore 1 2")
gdb.execute("continue")
gdb.execute("delete")
pcs, text = [], {}
for _ in range(maxn):
    pc = int(gdb.parse_and_eval("$pc"))
    if pc not in text:
        text[pc] = gdb.execute(f"x/i {pc:#x}", to_string=True).split(":", 1)[1].strip()
    pcs.append(pc)
    gdb.execute("nexti" if text[pc].startswith("call") else "stepi", to_string=True)
last = len(pcs) - 1
visits = [i for i in range(last) if pcs[i] == pcs[last]]
if not visits:
    raise gdb.GdbError("no loop within MAXN instructions")
with open(out, "w") as f:
    for pc in pcs[visits[-1]:last]:
        f.write(f"{pc - base:#x}\t{text[pc]}\n")
gdb.execute("kill")
