"""Quickstart: the robust law on the paper's perturbed plant, as a table and a figure.
Run: python examples/quickstart.py [FIGURE.png]   (needs pandas: pip install -e ".[pandas]")"""
import sys

import rc3r

out = sys.argv[1] if len(sys.argv) > 1 else "quickstart.png"
spec = rc3r.build_run(controller="robust", perturbed=True)  # Table 1 plant, Table 3 theta_0, rho = 186.8129
res, metrics = rc3r.execute(spec)                           # 10 s of continuous time
df = res.to_pandas()                                        # index t [s]; q, qd, qdes, e [rad], u [N m], ytr_norm
print(df[["e1", "e2", "e3"]].abs().max())                   # max|e| per joint [rad]
fig = res.plot("robust law, perturbed plant")               # a matplotlib Figure (backend untouched)
fig.savefig(out, dpi=110)
print(f"{len(df)} rows x {df.shape[1]} columns; figure: {out}")
