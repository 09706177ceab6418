import mitsuba as mi, numpy as np
mi.set_variant('scalar_rgb')
def load(p): return np.array(mi.Bitmap(p), dtype=np.float64)[..., :3]
for s in ('double','single'):
    ref = load(f'ref-{s}.exr')
    print(s, 'ref mean', ref.mean(axis=(0,1)))
    vs=[]; tops=[]
    for seed in range(1,7):
        e=(load(f'{s}-64-{seed}.exr')-ref)**2/(ref**2+1e-2)
        vs.append(e.mean()); pe=np.sort(e.sum(axis=2).ravel())[::-1]; tops.append(pe[:len(pe)//100].sum()/pe.sum())
    print(s, 'relMSE 64spp', ' '.join(f'{v:.5f}' for v in vs), 'mean %.5f'%np.mean(vs), 'top1%% share %.2f'%np.mean(tops))
