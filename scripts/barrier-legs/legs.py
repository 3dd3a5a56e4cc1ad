# Session 12 (docs/scaling.md, "The barrier taken apart"): the legs of each step from the
# CRASH_LEGS files of a run with stamps.patch applied. Usage: python3 legs.py /tmp/legs-TAG
# Analyse CRASH_LEGS files: master file (has m_ tags) and worker files (w_ tags).
import sys, glob, bisect, statistics as st
base = sys.argv[1]
files = glob.glob(base + ".*")
master = None; workers = []
for f in files:
    rows = [l.split() for l in open(f)]
    rows = [(int(t), tag, int(k)) for t, tag, k in rows]
    if rows and rows[0][1].startswith("m_"):
        master = rows
    else:
        workers.append(rows)
# master steps
steps = []
cur = None
for t, tag, k in master:
    if tag == "m_step":
        cur = {"m_step": t}
    elif cur is not None:
        cur.setdefault(f"{tag}{k}" if tag != "m_done" else tag, t)
        if tag == "m_done":
            steps.append(cur); cur = None
steps = [s for s in steps if all(x in s for x in ("m_sent0","m_sent1","m_got0","m_got1","m_dec1"))]
# worker event tuples: (w_got, w_dec, w_comp, w_sent)
wev = []
for rows in workers:
    ev = []; e = {}
    for t, tag, k in rows:
        e[tag] = t
        if tag == "w_sent":
            if "w_got" in e: ev.append(e)
            e = {}
    wev.append(ev)
# assign worker file to index: the one whose w_sent just precedes m_got0 most
def nearest_after(ev, t):
    starts = [e["w_got"] for e in ev]
    i = bisect.bisect_left(starts, t)
    return ev[i] if i < len(ev) else None
legs = {}
def add(k, v): legs.setdefault(k, []).append(v/1000)
for s in steps:
    per = []
    for ev in wev:
        e = nearest_after(ev, s["m_step"])
        if e is None or e["w_got"] > s["m_done"]: break
        per.append(e)
    if len(per) != 2: continue
    # which worker is index 0: its w_sent <= m_got0 and closer
    a, b = per
    if abs(s["m_got0"] - a["w_sent"]) > abs(s["m_got0"] - b["w_sent"]): a, b = b, a
    add("total exchange m_step->m_done", s["m_done"] - s["m_step"])
    add("master encode+queue 2 (m_step->m_sent1)", s["m_sent1"] - s["m_step"])
    for i, (e, k) in enumerate(((a, 0), (b, 1))):
        add(f"w{i} wake: m_sent1 -> w_got", e["w_got"] - s["m_sent1"])
        add(f"w{i} decode+compute+encode+queue (w_got->w_sent)", e["w_sent"] - e["w_got"])
        add(f"w{i}   compute (w_dec->w_comp)", e["w_comp"] - e["w_dec"])
        add(f"w{i} reply: w_sent -> m_got{k}", s[f"m_got{k}"] - e["w_sent"])
    add("m_got0 -> m_dec0 (return from block_on + decode)", s["m_dec0"] - s["m_got0"])
    add("m_dec0 -> m_got1", s["m_got1"] - s["m_dec0"])
    add("m_dec1 -> m_done", s["m_done"] - s["m_dec1"])
    add("first reply order: w1 before w0 (1=yes)", 1000 if b["w_sent"] < a["w_sent"] else 0)
print(f"{len(steps)} steps")
for k, v in legs.items():
    v.sort()
    print(f"{k:55s} median {st.median(v):8.1f}  p10 {v[len(v)//10]:8.1f}  p90 {v[len(v)*9//10]:8.1f} mean {st.mean(v):8.1f}")
