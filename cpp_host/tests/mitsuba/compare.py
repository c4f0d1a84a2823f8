#!/usr/bin/env python3
"""Compare mfrender with Mitsuba 3 (scalar_rgb) on the scenes of this folder, with a
statistical tolerance in the spirit of Mitsuba's own render tests: each renderer renders every
scene with K independent seeds; image means (per channel) must agree within
4.5 combined standard errors + `--rel-tol` (1 %) of the mean, and on 8x8-pixel blocks the
fraction of blocks differing by more than 5 standard errors + 2 % must stay below 2 % (this
catches local errors such as a seam that a mean would hide).

Exit status 77 (ctest: skipped) when Mitsuba 3 is not installed
(MF_SETUP_MITSUBA=1 scripts/setup.sh installs it).
usage: compare.py --mfrender PATH --work DIR [--runs K] [--spp N] [scene.xml ...]"""
import argparse, glob, math, os, shutil, struct, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--mfrender', required=True)
    ap.add_argument('--work', required=True)
    ap.add_argument('--runs', type=int, default=4)
    ap.add_argument('--spp', type=int, default=32)
    ap.add_argument('--rel-tol', type=float, default=0.01)
    ap.add_argument('scenes', nargs='*')
    a = ap.parse_args()
    try:
        import mitsuba as mi
    except ImportError:
        print('skipped: Mitsuba 3 is not installed (MF_SETUP_MITSUBA=1 scripts/setup.sh installs 3.9.1)')
        return 77
    mi.set_variant('scalar_rgb')
    mi.set_log_level(mi.LogLevel.Error)
    os.makedirs(a.work, exist_ok=True)
    # data files the scenes refer to
    subprocess.run([sys.executable, os.path.join(HERE, 'make_serialized.py'), os.path.join(a.work, 'torus.serialized')], check=True)
    subprocess.run([sys.executable, os.path.join(HERE, 'make_blob_vol.py'), a.work], check=True)
    subprocess.run([sys.executable, os.path.join(HERE, 'make_normal_png.py'), a.work], check=True)
    subprocess.run([sys.executable, os.path.join(HERE, 'make_attribute_ply.py'), a.work], check=True)
    scenes = a.scenes or sorted(glob.glob(os.path.join(HERE, '*.xml')))
    passed = failed = 0
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        local = os.path.join(a.work, name + '.xml')
        shutil.copy(scene, local)  # beside the generated data files
        mf_runs, mi_runs = [], []
        for k in range(a.runs):
            out = os.path.join(a.work, f'{name}_mf{k}.exr')
            subprocess.run([a.mfrender, local, '-o', out, '--quiet', '--seed', str(1000 + k), '-D', f'spp={a.spp}'], check=True)
            mf_runs.append(read(mi, out))
            sc = mi.load_file(local, spp=a.spp)
            img = mi.render(sc, seed=2000 + k)
            mi.util.write_bitmap(os.path.join(a.work, f'{name}_mi{k}.exr'), img, write_async=False)
            mi_runs.append((img.shape[1], img.shape[0], rgb_channels(img)))
        ok, report = judge(mf_runs, mi_runs, a.rel_tol)
        print(f'[{"PASS" if ok else "FAIL"}] {name}: {report}')
        passed += ok
        failed += not ok
    print(f'{passed} passed, {failed} failed')
    return 0 if failed == 0 else 1

def rgb_channels(img):
    """R, G, B of a rendered tensor: the moment integrator adds AOV channels after them."""
    h, w, c = img.shape
    flat = list(img.array)
    return flat if c == 3 else [flat[i * c + k] for i in range(h * w) for k in range(3)]

def read(mi, path):
    b = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    w, h = b.size()
    flat = list(mi.TensorXf(b).array)
    return w, h, flat

def judge(mf_runs, mi_runs, rel_tol):
    w, h, _ = mf_runs[0]
    K = len(mf_runs)
    def channel_means(run):
        _, _, f = run
        n = len(f) // 3
        return [sum(f[c::3]) / n for c in range(3)]
    msgs, ok = [], True
    for c in range(3):
        a = [channel_means(r)[c] for r in mf_runs]
        b = [channel_means(r)[c] for r in mi_runs]
        ma, mb = sum(a) / K, sum(b) / K
        se = math.sqrt(var(a) / K + var(b) / K)
        tol = 4.5 * se + rel_tol * abs(mb)
        good = abs(ma - mb) <= tol
        ok &= good
        msgs.append(f'{"RGB"[c]} {ma:.5f} vs {mb:.5f} ({(ma - mb) / mb * 100 if mb else 0:+.2f} %, se {se:.1e})')
    # 8x8 blocks of the channel sum
    B = 8
    bx, by = w // B, h // B
    def blocks(run):
        _, _, f = run
        out = []
        for j in range(by):
            for i in range(bx):
                s = 0.0
                for y in range(j * B, j * B + B):
                    row = y * w
                    for x in range(i * B, i * B + B):
                        p = 3 * (row + x)
                        s += f[p] + f[p + 1] + f[p + 2]
                out.append(s / (B * B))
        return out
    A = [blocks(r) for r in mf_runs]
    Bm = [blocks(r) for r in mi_runs]
    bad = 0
    relmse_num = relmse_den = 0.0
    for t in range(bx * by):
        a = [A[k][t] for k in range(K)]
        b = [Bm[k][t] for k in range(K)]
        ma, mb = sum(a) / K, sum(b) / K
        se = math.sqrt(var(a) / K + var(b) / K)
        if abs(ma - mb) > 5 * se + 0.02 * abs(mb) + 1e-6:
            bad += 1
        relmse_num += (ma - mb) ** 2
        relmse_den += mb * mb
    frac = bad / max(1, bx * by)
    ok &= frac <= 0.02
    msgs.append(f'blocks off {bad}/{bx * by}, block rel. MSE {relmse_num / max(relmse_den, 1e-30):.2e}')
    return ok, '; '.join(msgs)

def var(x):
    m = sum(x) / len(x)
    return sum((v - m) ** 2 for v in x) / max(1, len(x) - 1)

if __name__ == '__main__':
    sys.exit(main())
