# relMSE of renders against a reference: python relmse.py ref.exr prefix-spp (seeds 1..N found by glob)
import sys, glob, OpenEXR, numpy as np
def load(p):
    with OpenEXR.File(p) as f:
        ch = f.channels()
        if 'RGB' in ch: return np.asarray(ch['RGB'].pixels, dtype=np.float64)[..., :3]
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in 'RGB'], -1)
ref = load(sys.argv[1])
for prefix in sys.argv[2:]:
    vs = []
    for p in sorted(glob.glob(prefix + '-*.exr')):
        img = load(p)
        e = (img - ref) ** 2 / (ref ** 2 + 1e-2)
        vs.append(e.mean())
    print(prefix, 'n', len(vs), 'relMSE mean %.6f' % np.mean(vs), 'median %.6f' % np.median(vs), ' '.join('%.5f' % v for v in vs))
