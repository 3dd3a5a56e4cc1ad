# Session 36 (docs/performance.md, "Session 36"): the legs of each split step from the
# CRASH_STAMPS files of a run with stamps.patch applied (master and worker timestamps on
# CLOCK_MONOTONIC, so comparable across the processes of one host): medians over steps
# 1000-2000 of when each worker got its Step, ended phase 1, the inner forces and the
# halo wait, replied, and when the master read, decoded and merged the replies.
# Usage: python3 legs.py STAMPS_DIR
import glob, statistics as st, sys
d = sys.argv[1]
def load(f):
    return [(int(t), g) for t, g in (l.split() for l in open(f))]
m = load(glob.glob(d + "/master-*.txt")[0])
ws = [load(f) for f in sorted(glob.glob(d + "/worker-*.txt"))]
# master steps
steps = []
cur = None
for t, g in m:
    if g == "m_step":
        if cur: steps.append(cur)
        cur = {"m_step": t}
    elif cur is not None and g not in cur:
        cur[g] = t
if cur: steps.append(cur)
# map worker file -> index by the first step's sent vs read
import bisect
def events_in(w, a, b):
    out = {}
    for t, g in w:
        if a <= t < b and g not in out:
            out[g] = t
    return out
rows = []
for k in range(1000, min(len(steps) - 1, 2000)):
    s = steps[k]; nxt = steps[k + 1]["m_step"]
    if not all(x in s for x in ("m_sent0", "m_sent1", "m_read0", "m_read1", "m_dec1", "m_merged")):
        continue
    we = [events_in(w, s["m_step"], nxt + 400000) for w in ws]
    if not all(all(x in e for x in ("w_got", "w_p1", "w_inner", "w_halo", "w_handled", "w_sent")) for e in we):
        continue
    rows.append((s, nxt, we))
print("steps analysed", len(rows))
def med(xs): return st.median(xs) / 1000
def mean(xs): return st.mean(xs) / 1000
# identify index: worker whose w_sent is closest before m_read0
def col(f):
    return [f(s, nxt, we) for s, nxt, we in rows]
# per worker, relative to m_step
for i in range(len(ws)):
    print(f"worker file {i}:",
          "got", round(med(col(lambda s,n,we: we[i]['w_got'] - s['m_step'])),1),
          "p1", round(med(col(lambda s,n,we: we[i]['w_p1'] - s['m_step'])),1),
          "inner", round(med(col(lambda s,n,we: we[i]['w_inner'] - s['m_step'])),1),
          "halo", round(med(col(lambda s,n,we: we[i]['w_halo'] - s['m_step'])),1),
          "handled", round(med(col(lambda s,n,we: we[i]['w_handled'] - s['m_step'])),1),
          "sent", round(med(col(lambda s,n,we: we[i]['w_sent'] - s['m_step'])),1))
print("master:", {g: round(med(col(lambda s,n,we,g=g: s[g] - s['m_step'])),1) for g in ("m_sent0","m_sent1","m_read0","m_dec0","m_read1","m_dec1","m_merged")}, "next step", round(med(col(lambda s,n,we: n - s['m_step'])),1))
# critical path pieces
last_sent = col(lambda s,n,we: max(e['w_sent'] for e in we))
print("last worker sent -> master merged:", round(med([s['m_merged'] - ls for (s,n,we), ls in zip(rows, last_sent)]),1))
print("master merged -> next m_step:", round(med(col(lambda s,n,we: n - s['m_merged'])),1))
print("last p1 - first p1 (phase-1 imbalance):", round(med(col(lambda s,n,we: abs(we[0]['w_p1']-we[1]['w_p1']))),1))
print("halo wait per worker (halo - inner):", [round(med(col(lambda s,n,we,i=i: we[i]['w_halo']-we[i]['w_inner'])),1) for i in range(2)])
print("handled->sent (encode+write):", [round(med(col(lambda s,n,we,i=i: we[i]['w_sent']-we[i]['w_handled'])),1) for i in range(2)])
print("m_sent -> w_got:", [round(med(col(lambda s,n,we,i=i: we[i]['w_got']-min(s['m_sent0'], s['m_sent1']))),1) for i in range(2)])
print("w_sent -> m_read (matching):", [round(med(col(lambda s,n,we,i=i: min(abs(s['m_read0']-we[i]['w_sent']), abs(s['m_read1']-we[i]['w_sent'])))),1) for i in range(2)])
