import numpy as np, OpenEXR
W, H = 128, 65
u = (np.arange(W) + 0.5) / W
v = np.arange(H) / (H - 1)
phi, theta = np.meshgrid(u * 2 * np.pi, v * np.pi)
d = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], -1)
sw = np.sin(theta)
def save(name, lum, tint=(1.0, 1.0, 1.0)):
    rgb = (lum[..., None] * np.array(tint)).astype(np.float32)
    mean = (lum * sw).sum() / sw.sum()
    print(name, 'peak/mean %.2f' % (lum.max() / mean))
    OpenEXR.File({'compression': OpenEXR.ZIP_COMPRESSION, 'type': OpenEXR.scanlineimage}, {'RGB': rgb}).write(f'/tmp/fh/{name}.exr')
save('hemi', np.where(d[..., 1] > 0, 1.0, 0.05))
s = np.array([0.5, 0.7071, 0.5]); s /= np.linalg.norm(s)
c = np.clip(d @ s, 0, 1)
for k, p in ((3.0, 4), (12.0, 8), (60.0, 32)):
    save(f'cap-{k:g}-{p}', 0.3 + 0.3 * (d[..., 1] > 0) + k * c ** p)
