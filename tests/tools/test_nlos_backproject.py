#!/usr/bin/env python3
"""Tests tools/nlos_backproject on captures synthesised analytically in numpy.

For every (laser point, sensor point) pair the hidden target's samples (a point, or a small patch
parallel to the wall) put their response in the bin of their exact path length, in y-tal's HDF5
layout (enums as y-tal writes them, None as h5py.Empty, scene_info as YAML text). The
reconstruction's maximum must lie at the target's depth (within one bin width of round-trip time,
i.e. delta_t / 2 of depth, plus half a depth step) and in front of the right wall point (within one
grid cell). Also: the vectorised, chunked back-projection against a plain loop, the bin convention,
and bad input (a missing key names the key, exit code 2).

Run: python3 tests/tools/test_nlos_backproject.py   (needs numpy and h5py; unittest only; re-runs
itself under /usr/bin/python3 when the python3 on PATH lacks them)
"""
import importlib.machinery
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import unittest

try:
    import numpy as np
    import h5py
except ImportError:  # pragma: no cover - depends on the machine
    # A python3 without numpy/h5py (e.g. pyenv's ahead of the system one on PATH): use the
    # system's, as the C++ tests do (docs/developer/tests.md), or say what is missing.
    if os.path.realpath(sys.executable) != os.path.realpath('/usr/bin/python3') \
            and os.path.exists('/usr/bin/python3'):
        os.execv('/usr/bin/python3', ['/usr/bin/python3', os.path.abspath(__file__)] + sys.argv[1:])
    sys.exit('test_nlos_backproject: needs numpy and h5py '
             '(apt-get install python3-numpy python3-h5py)')

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOL = os.path.join(ROOT, 'tools', 'nlos_backproject')


def load_tool():
    loader = importlib.machinery.SourceFileLoader('nlos_backproject', TOOL)
    spec = importlib.util.spec_from_loader('nlos_backproject', loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


bp = load_tool()

# y-tal's enums (tal/enums.py): HFormat, GridFormat, VolumeFormat.
H_FORMAT = {'UNKNOWN': 0, 'T_Sx_Sy': 1, 'T_Lx_Ly_Sx_Sy': 2, 'T_Si': 3, 'T_Li_Si': 4,
            'F_Sx_Sy': 10, 'F_Lx_Ly_Sx_Sy': 11, 'F_Si': 12, 'F_Li_Si': 13}
GRID_FORMAT = {'UNKNOWN': 0, 'N_3': 1, 'X_Y_3': 2}
VOLUME_FORMAT = {'UNKNOWN': 0, 'N_3': 1, 'X_Y_Z_3': 2, 'X_Y_3': 3}

DT = 0.01        # bin width, m of optical path
NT = 600         # bins
ORIGIN = np.array([-0.5, 0.0, 0.25])  # laser_xyz = sensor_xyz, y-tal's default


def wall_grid(nx, ny, half=0.5):
    """Cell centres of an nx x ny grid on the wall z = 0, x along the first index (as y-tal)."""
    xs = np.linspace(-half, half, 2 * nx + 1)[1::2]
    ys = np.linspace(-half, half, 2 * ny + 1)[1::2]
    g = np.stack(np.meshgrid(xs, ys, indexing='ij') + [np.zeros((nx, ny))], axis=-1)
    return g.astype(np.float32)


def patch(center, size, n):
    """n x n samples of a square patch parallel to the wall."""
    off = np.linspace(-size / 2, size / 2, n)
    a, b = np.meshgrid(off, off, indexing='ij')
    return np.stack([center[0] + a.ravel(), center[1] + b.ravel(),
                     np.full(n * n, center[2])], axis=-1)


def synth_H(targets, lasers, sensors, paired, accounts, t_start=0.0):
    """H (T, NL, NS) or, paired, (T, NS): 1 per target sample in the bin of its exact path."""
    lasers = lasers.reshape(-1, 3).astype(np.float64)
    sensors = sensors.reshape(-1, 3).astype(np.float64)
    d_lp = np.linalg.norm(lasers[:, None, :] - targets[None, :, :], axis=2)   # (NL, M)
    d_ps = np.linalg.norm(sensors[:, None, :] - targets[None, :, :], axis=2)  # (NS, M)
    d1 = np.linalg.norm(lasers - ORIGIN, axis=1) if accounts else np.zeros(len(lasers))
    d4 = np.linalg.norm(sensors - ORIGIN, axis=1) if accounts else np.zeros(len(sensors))
    if paired:
        t = d1[:, None] + d_lp + d_ps + d4[:, None]                            # (NS, M)
        H = np.zeros((NT, len(sensors)), np.float32)
        bins = np.floor((t - t_start) / DT).astype(int)
        for s in range(len(sensors)):
            for b in bins[s]:
                if 0 <= b < NT:
                    H[b, s] += 1
        return H
    t = (d1[:, None, None] + d_lp[:, None, :] + d_ps[None, :, :]
         + d4[None, :, None])                                                  # (NL, NS, M)
    H = np.zeros((NT, len(lasers), len(sensors)), np.float32)
    bins = np.floor((t - t_start) / DT).astype(int)
    for li in range(len(lasers)):
        for s in range(len(sensors)):
            for b in bins[li, s]:
                if 0 <= b < NT:
                    H[b, li, s] += 1
    return H


def write_tal_h5(path, H, h_format, sensor_grid, laser_grid, accounts, t_start=0.0, omit=(),
                 override=None):
    """A capture in y-tal's HDF5 layout (the keys and encodings of tal.io.write_hdf5)."""
    nx, ny = sensor_grid.shape[:2]
    lx, ly = laser_grid.shape[:2]
    data = {
        'H': H,
        'H_format': ('enum', H_FORMAT, h_format),
        'sensor_xyz': ORIGIN.astype(np.float32),
        'sensor_grid_xyz': sensor_grid,
        'sensor_grid_normals': np.broadcast_to(np.float32([0, 0, 1]), (nx, ny, 3)).copy(),
        'sensor_grid_format': ('enum', GRID_FORMAT, 'X_Y_3'),
        'laser_xyz': ORIGIN.astype(np.float32),
        'laser_grid_xyz': laser_grid,
        'laser_grid_normals': np.broadcast_to(np.float32([0, 0, 1]), (lx, ly, 3)).copy(),
        'laser_grid_format': ('enum', GRID_FORMAT, 'X_Y_3'),
        'volume_format': None,
        'delta_t': np.float64(DT),
        't_start': np.float64(t_start),
        't_accounts_first_and_last_bounces': bool(accounts),
        'scene_info': "{original_format: HDF5_TAL, note: synthesised by test_nlos_backproject}\n",
    }
    data.update(override or {})
    with h5py.File(path, 'w') as f:
        for key, value in data.items():
            if key in omit:
                continue
            if value is None:
                f[key] = h5py.Empty(float)
            elif isinstance(value, tuple) and value[0] == 'enum':
                _, mapping, name = value
                ds = f.create_dataset(key, (1,), dtype=h5py.enum_dtype(mapping, basetype='i'))
                ds[0] = mapping[name]
            else:
                f[key] = value


def run_tool(*args):
    return subprocess.run([sys.executable, TOOL] + [str(a) for a in args],
                          capture_output=True, text=True, timeout=600)


class Reconstruction(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def check_max(self, summary, sensor_grid, target, depth_step):
        """Depth within one bin of round trip (+ half a depth step); wall cell within one cell."""
        depth_err = abs(summary['max_depth_m'] - target[2])
        self.assertLessEqual(depth_err, DT / 2 + depth_step / 2 + 1e-9, summary)
        cell = sensor_grid[1, 1, :2] - sensor_grid[0, 0, :2]
        pos = np.array(summary['max_position_m'])
        self.assertTrue(np.all(np.abs(pos[:2] - target[:2]) <= cell + 1e-9), (summary, target))
        # and the voxel's column is in front of the wall point nearest the target (+-1 cell)
        d = np.linalg.norm(sensor_grid[..., :2] - target[:2], axis=-1)
        want = np.unravel_index(np.argmin(d), d.shape)
        got = summary['max_voxel'][:2]
        self.assertLessEqual(max(abs(got[0] - want[0]), abs(got[1] - want[1])), 1, summary)
        self.assertLess(abs(summary['max_position_m'][2] - summary['max_depth_m']), 1e-5)

    def reconstruct(self, h5, depth_min, depth_max, nz, filt='none'):
        out = self.path('vol.npy')
        r = run_tool(h5, '--out', out, '--depth-min', depth_min, '--depth-max', depth_max,
                     '--voxels', nz, '--filter', filt)
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.strip().splitlines()
        self.assertEqual(len(lines), 1, r.stdout)
        summary = json.loads(lines[0])
        vol = np.load(out)
        self.assertEqual(list(vol.shape), summary['volume_shape'])
        self.assertEqual(tuple(np.unravel_index(np.argmax(vol), vol.shape)),
                         tuple(summary['max_voxel']))
        return summary

    def test_confocal_point_and_patch(self):
        grid = wall_grid(16, 16)
        # Targets in front of wall points (the voxel columns): a delta in one bin blurs over
        # about one bin laterally too, so a target between columns of this coarse grid would
        # move the maximum in depth. (Kernel.test_matches_a_plain_loop covers any position.)
        point = np.array([*grid[9, 5, :2], 0.6])
        centre = np.array([*grid[6, 11, :2], 0.45])
        cases = [('point', point[None], point), ('patch', patch(centre, 0.08, 5), centre)]
        nz, d0, d1 = 121, 0.2, 0.8
        step = (d1 - d0) / (nz - 1)
        for name, targets, centre in cases:
            for accounts in (False, True):
                for filt in ('none', 'laplacian'):
                    with self.subTest(target=name, accounts=accounts, filter=filt):
                        H = synth_H(targets, grid, grid, paired=True, accounts=accounts)
                        self.assertGreater(H.sum(), 0)
                        h5 = self.path(f'confocal_{name}_{accounts}.h5')
                        write_tal_h5(h5, H.reshape(NT, 16, 16), 'T_Sx_Sy', grid, grid, accounts)
                        s = self.reconstruct(h5, d0, d1, nz, filt)
                        self.assertEqual(s['kind'], 'confocal')
                        self.assertEqual(s['wall_normal'], [0, 0, 1])
                        self.check_max(s, grid, centre, step)

    def test_exhaustive_2x2_lasers(self):
        sensors = wall_grid(12, 12)
        lasers = wall_grid(2, 2, half=0.3)
        target = np.array([*sensors[3, 7, :2], 0.55])
        nz, d0, d1 = 81, 0.3, 0.7
        for accounts in (False, True):
            with self.subTest(accounts=accounts):
                H = synth_H(target[None], lasers, sensors, paired=False, accounts=accounts)
                h5 = self.path(f'exhaustive_{accounts}.h5')
                write_tal_h5(h5, H.reshape(NT, 2, 2, 12, 12), 'T_Lx_Ly_Sx_Sy', sensors, lasers,
                             accounts)
                s = self.reconstruct(h5, d0, d1, nz)
                self.assertEqual(s['kind'], 'exhaustive')
                self.check_max(s, sensors, target, (d1 - d0) / (nz - 1))

    def test_single_laser_point(self):
        sensors = wall_grid(12, 12)
        laser = np.float32([[[0.05, -0.05, 0.0]]])
        target = np.array([*sensors[8, 9, :2], 0.5])
        H = synth_H(target[None], laser, sensors, paired=False, accounts=True, t_start=0.5)
        h5 = self.path('single.h5')
        write_tal_h5(h5, H.reshape(NT, 12, 12), 'T_Sx_Sy', sensors, laser, True, t_start=0.5)
        s = self.reconstruct(h5, 0.3, 0.7, 81)
        self.assertEqual(s['kind'], 'single')
        self.check_max(s, sensors, target, 0.005)

    def test_confocal_point_lists(self):
        # H_format T_Si: H (T, Si), grids as N x 3 lists (GridFormat N_3), in a shuffled order.
        grid = wall_grid(10, 10)
        order = np.random.default_rng(3).permutation(100)
        pts = grid.reshape(-1, 3)[order]
        target = np.array([*grid[2, 6, :2], 0.5])
        H = synth_H(target[None], pts, pts, paired=True, accounts=True)
        h5 = self.path('points.h5')
        write_tal_h5(h5, H, 'T_Si', grid, grid, True, override={
            'sensor_grid_xyz': pts, 'laser_grid_xyz': pts,
            'sensor_grid_normals': None, 'laser_grid_normals': None,
            'sensor_grid_format': ('enum', GRID_FORMAT, 'N_3'),
            'laser_grid_format': ('enum', GRID_FORMAT, 'N_3')})
        s = self.reconstruct(h5, 0.3, 0.7, 81)
        self.assertEqual(s['kind'], 'confocal')
        self.assertEqual(s['volume_shape'], [10, 10, 81])
        self.assertEqual(s['wall_normal'], [0, 0, 1])  # turned towards sensor_xyz
        self.check_max(s, grid, target, 0.005)

    def test_default_depth_range_and_lateral(self):
        grid = wall_grid(8, 8)
        target = np.array([*grid[4, 3, :2], 0.7])
        H = synth_H(target[None], grid, grid, paired=True, accounts=False)
        h5 = self.path('defaults.h5')
        write_tal_h5(h5, H.reshape(NT, 8, 8), 'T_Sx_Sy', grid, grid, False)
        r = run_tool(h5, '--voxels', 300)
        self.assertEqual(r.returncode, 0, r.stderr)
        s = json.loads(r.stdout)
        # deepest visible depth: (t_start + NT * delta_t) / 2 = 3 m; 300 steps of 1 cm from 1 cm
        self.assertAlmostEqual(s['depth_range_m'][1], 3.0)
        self.assertAlmostEqual(s['depth_range_m'][0], 0.01)
        self.assertEqual(s['volume_shape'], [8, 8, 300])
        self.assertIsNone(s['out'])
        self.check_max(s, grid, target, 0.01)


class Kernel(unittest.TestCase):
    """The module's functions, without files."""

    def capture(self, H, L, S, paired, accounts, t_start=0.0):
        return bp.Capture('mem', 'test', H, paired, L, S, (len(S),), None,
                          ORIGIN, ORIGIN, DT, t_start, accounts)

    def test_bin_centres_and_linear_interpolation(self):
        # One laser, one sensor, both at the origin of the wall; H is 1 in bin 10 only.
        H = np.zeros((NT, 1, 1), np.float32)
        H[10] = 1
        cap = self.capture(H, np.zeros((1, 3)), np.zeros((1, 3)), False, False, t_start=0.1)
        # bin 10 covers path lengths [0.2, 0.21); its centre 0.205 m = depth 0.1025
        depths = np.array([0.1025, 0.1025 - DT / 4, 0.1025 + DT / 4, 0.1025 + DT / 2,
                           0.1025 - DT / 2, 0.1025 + DT])
        xyz = np.stack([np.zeros_like(depths), np.zeros_like(depths), depths], axis=-1)
        vol = bp.backproject(cap, xyz)
        np.testing.assert_allclose(vol, [1, 0.5, 0.5, 0, 0, 0], atol=1e-9)

    def test_matches_a_plain_loop(self):
        rng = np.random.default_rng(7)
        S = np.concatenate([rng.uniform(-0.5, 0.5, (9, 2)), np.zeros((9, 1))], axis=1)
        L = np.concatenate([rng.uniform(-0.5, 0.5, (3, 2)), np.zeros((3, 1))], axis=1)
        xyz = rng.uniform([-0.5, -0.5, 0.1], [0.5, 0.5, 1.5], (4, 5, 6, 3))
        H3 = rng.random((NT, 3, 9)).astype(np.float32)
        H2 = rng.random((NT, 9)).astype(np.float32)

        def ref(H, Ls, paired, accounts):
            out = np.zeros(xyz.shape[:-1])
            # H as a piecewise-linear function through its bin centres, zero one bin outside
            centres = (np.arange(-1, NT + 1) + 0.5) * DT
            for idx in np.ndindex(out.shape):
                x = xyz[idx]
                pairs = ([(j, j) for j in range(len(S))] if paired
                         else [(i, j) for i in range(len(Ls)) for j in range(len(S))])
                for i, j in pairs:
                    t = np.linalg.norm(Ls[i] - x) + np.linalg.norm(x - S[j])
                    if accounts:
                        t += np.linalg.norm(ORIGIN - Ls[i]) + np.linalg.norm(S[j] - ORIGIN)
                    trace = np.concatenate([[0.0], H[:, j] if paired else H[:, i, j], [0.0]])
                    out[idx] += np.interp(t, centres, trace, left=0.0, right=0.0)
            return out

        for paired, H, Ls in ((False, H3, L), (True, H2, S + 0.01)):
            for accounts in (False, True):
                with self.subTest(paired=paired, accounts=accounts):
                    cap = self.capture(H, Ls, S, paired, accounts)
                    got = bp.backproject(cap, xyz, max_bytes=5000)  # chunks of a few voxels
                    np.testing.assert_allclose(got, ref(H, Ls, paired, accounts), rtol=1e-6,
                                               atol=1e-9)

    def test_laplacian_along_depth(self):
        v = np.array([[[0, 1, 4, 1, 0, 0, 3, 6]]], float)
        np.testing.assert_allclose(bp.laplacian_depth(v), [[[-1, -2, 6, -2, -1, -3, 0, 3]]])


class BadInput(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)
        self.grid = wall_grid(4, 4)
        self.H = np.zeros((NT, 4, 4), np.float32)
        self.H[100] = 1

    def write(self, accounts=False, **kw):
        path = os.path.join(self.tmp.name, 'bad.h5')
        write_tal_h5(path, self.H, 'T_Sx_Sy', self.grid, self.grid, accounts, **kw)
        return path

    def refused(self, path, words, *args):
        r = run_tool(path, '--voxels', 4, *args)
        self.assertEqual(r.returncode, 2, (r.stdout, r.stderr))
        self.assertEqual(r.stdout, '')
        for w in words:
            self.assertIn(w, r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)  # no traceback

    def test_missing_keys_are_named(self):
        for key in ('H', 'H_format', 'delta_t', 't_start', 'sensor_grid_xyz', 'laser_grid_xyz',
                    't_accounts_first_and_last_bounces'):
            with self.subTest(key=key):
                self.refused(self.write(omit=(key,)), ["missing key '%s'" % key])

    def test_first_and_last_bounces_need_the_origins(self):
        for key in ('laser_xyz', 'sensor_xyz'):
            with self.subTest(key=key):
                self.refused(self.write(accounts=True, omit=(key,)), ["missing key '%s'" % key])
        # not needed when the capture leaves those legs out
        r = run_tool(self.write(accounts=False, omit=('laser_xyz', 'sensor_xyz')), '--voxels', 4)
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_inconsistent_or_unsupported(self):
        self.refused(self.write(override={'t_start': None}), ["'t_start' is empty"])
        self.refused(self.write(override={'delta_t': np.float64(0)}), ["'delta_t'"])
        self.refused(self.write(override={'sensor_grid_xyz': wall_grid(4, 5)}),
                     ["'sensor_grid_xyz'", '20 points'])
        self.refused(self.write(override={'laser_grid_xyz': wall_grid(2, 3)}), ["'laser_grid_xyz'"])
        self.refused(self.write(override={'H': self.H[:, :, 0]}), ["'H'", 'T_Sx_Sy'])
        self.refused(self.write(override={'H_format': ('enum', H_FORMAT, 'F_Sx_Sy')}),
                     ["'H_format'", 'frequency'])
        bad = self.H.copy()
        bad[0, 0, 0] = np.nan
        self.refused(self.write(override={'H': bad}), ["'H'", 'non-finite'])
        self.refused(os.path.join(self.tmp.name, 'absent.h5'), ['no such file'])

    def test_bad_options(self):
        ok = self.write()
        self.refused(ok, ['--depth-max'], '--depth-min', 1, '--depth-max', 0.5)
        self.refused(ok, ['--out', '.npy'], '--out', os.path.join(self.tmp.name, 'v.txt'))


if __name__ == '__main__':
    unittest.main()
