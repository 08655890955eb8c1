#!/usr/bin/env python3
"""A rendered NLOS capture closes the loop (issue 35): `tpb render` of a confocal scan of a planar
target writes capture.h5; tools/check_nlos_hdf5 (the NLOS toolkit's read rules) accepts it; its
bins of every wall point sum to the wall point's steady value (a bin holds the response integrated
over it); scene_info's ground truth sees the target at its depth; and tools/nlos_backproject finds
the target at its depth (within one bin of round-trip time plus a depth step) in front of the right
wall point (within one grid cell). An exhaustive scan's file is accepted too, with H of shape
(T, Lx, Ly, Sx, Sy).

Run: python3 tests/tools/test_nlos_capture.py --tpb build/tpb   (CTest: nlos_capture_roundtrip)
"""
import argparse
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
    import yaml
except ImportError:  # pragma: no cover - depends on the machine
    if os.path.realpath(sys.executable) != os.path.realpath('/usr/bin/python3') \
            and os.path.exists('/usr/bin/python3'):
        os.execv('/usr/bin/python3', ['/usr/bin/python3', os.path.abspath(__file__)] + sys.argv[1:])
    sys.exit('test_nlos_capture: needs numpy, h5py and yaml '
             '(apt-get install python3-numpy python3-h5py python3-yaml)')

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TPB = os.path.join(ROOT, 'build', 'tpb')
TARGET_Z = 1.0  # the target's distance from the wall, m


def scene(scan, origin):
    return {
        "version": 1,
        "camera": {"type": "relay_wall", "position": [-0.5, 0, 0.25], "wall": "relay", "resolution": [8, 8],
                   "time_origin": origin, "scan": scan},
        # The wall's own response (the laser spot, t ~ 0 timed from the wall) falls before the film.
        "film": {"start_m": 0.5 if origin == "wall" else 2.5, "bin_width_m": 0.02, "bins": 200},
        "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
        "shapes": [{"name": "relay", "type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0],
                    "edge_v": [0, 2, 0], "material": "white"},
                   {"name": "target", "type": "quad", "corner": [-0.25, -0.25, TARGET_Z], "edge_u": [0, 0.5, 0],
                    "edge_v": [0.5, 0, 0], "material": "white"}],
        "lights": [{"name": "laser", "type": "laser", "position": [-0.5, 0, 0.25], "power": 1}],
        "render": {"photons_per_pass": 20000, "surface_radius": 0.05, "radius": 0.01, "max_depth": 4,
                   "seed": 7, "passes": 6},
    }


def render(tmp, name, scan, origin):
    path = os.path.join(tmp, name + '.json')
    with open(path, 'w') as f:
        json.dump(scene(scan, origin), f)
    out = os.path.join(tmp, name)
    r = subprocess.run([TPB, 'render', path, '-o', out, '--no-frames', '--quiet'], capture_output=True, text=True)
    if r.returncode != 0:
        raise AssertionError('tpb render failed: ' + r.stderr)
    return os.path.join(out, 'capture.h5')


def load_backproject():
    loader = importlib.machinery.SourceFileLoader('nlos_backproject', os.path.join(ROOT, 'tools', 'nlos_backproject'))
    spec = importlib.util.spec_from_loader('nlos_backproject', loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


class NlosCapture(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def check_file(self, h5):
        r = subprocess.run([sys.executable, os.path.join(ROOT, 'tools', 'check_nlos_hdf5'), h5],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)

    def test_confocal_capture_reconstructs_the_target(self):
        bp = load_backproject()
        for origin in ('wall', 'sensor'):
            with self.subTest(origin=origin):
                h5 = render(self.tmp.name, 'confocal_' + origin, {"mode": "confocal", "laser": "laser"}, origin)
                self.check_file(h5)
                with h5py.File(h5, 'r') as f:
                    H = f['H'][()]
                    self.assertEqual(H.shape, (200, 8, 8))
                    self.assertEqual(bool(f['t_accounts_first_and_last_bounces'][()]), origin == 'sensor')
                    self.assertAlmostEqual(float(f['delta_t'][()]), 0.02)
                    info = yaml.safe_load(f['scene_info'][()])
                # Ground truth: the wall points in front of the target see it at TARGET_Z.
                depth = info['ground_truth']['depth']
                self.assertAlmostEqual(depth[3][3], TARGET_Z, places=6)
                self.assertAlmostEqual(depth[4][4], TARGET_Z, places=6)
                self.assertIsNone(depth[0][0])
                # Every number is a number to a YAML reader (not a string such as "1e-17").
                for row_d, row_n in zip(depth, info['ground_truth']['normals']):
                    for d, n in zip(row_d, row_n):
                        self.assertTrue(d is None or isinstance(d, (int, float)), d)
                        self.assertTrue(n is None or all(isinstance(c, (int, float)) for c in n), n)
                self.assertEqual(info['tpb']['scan'], 'confocal')
                cap = bp.read_capture(h5)
                grid = bp.make_grid(cap, 0.3, 2.0, 86)
                vol = bp.backproject(cap, grid.xyz)
                s = bp.summarize(vol, grid)
                step = 1.7 / 85
                self.assertLessEqual(abs(s['max_depth_m'] - TARGET_Z), 0.02 / 2 + step,
                                     'depth %s' % s['max_depth_m'])
                # In front of the target: within one grid cell (0.25 m) of its 0.5 m square.
                x, y = s['max_position_m'][0], s['max_position_m'][1]
                self.assertLessEqual(abs(x), 0.25 + 0.25, s)
                self.assertLessEqual(abs(y), 0.25 + 0.25, s)

    def test_bins_integrate_the_response(self):
        # Timed from the wall, with the film covering everything after the laser spot's own
        # response: each wall point's bins sum to its part of the steady image that arrived inside.
        h5 = render(self.tmp.name, 'sums', {"mode": "confocal", "laser": "laser"}, 'wall')
        out = os.path.dirname(h5)
        with h5py.File(h5, 'r') as f:
            H = f['H'][()]
        with open(os.path.join(out, 'summary.json')) as f:
            summary = json.load(f)
        self.assertGreater(H.sum(), 0.0)
        self.assertTrue(np.all(np.isfinite(H)))
        self.assertTrue(np.all(H >= 0.0))
        # Against an .npy export of the same render: H[k, sx, sy] is the luminance of pixel (sx, sy).
        vol_dir = os.path.join(self.tmp.name, 'sums_npy')
        r = subprocess.run([TPB, 'render', os.path.join(self.tmp.name, 'sums.json'), '-o', vol_dir, '--no-frames',
                            '--quiet', '--npy'], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        vol = np.load(os.path.join(vol_dir, 'transient.npy'))  # (H, W, bins, 3)
        lum = vol @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)
        np.testing.assert_allclose(H, np.transpose(lum, (2, 1, 0)), rtol=1e-5, atol=1e-12)
        self.assertIn('film_energy', summary)

    def test_exhaustive_capture_is_read_as_one(self):
        h5 = render(self.tmp.name, 'exhaustive', {"mode": "exhaustive", "laser": "laser", "grid": [2, 3]}, 'wall')
        self.check_file(h5)
        with h5py.File(h5, 'r') as f:
            self.assertEqual(f['H'].shape, (200, 2, 3, 8, 8))
            laser = f['laser_grid_xyz'][()]
            sensor = f['sensor_grid_xyz'][()]
        self.assertEqual(laser.shape, (2, 3, 3))
        # tal's laser_grid_xyz[lx, ly] is the centre of cell (lx, ly) of the 2 x 3 grid on the wall.
        np.testing.assert_allclose(laser[1, 2], [-1 + 1.5 * 2 / 2, -1 + 2.5 * 2 / 3, 0], atol=1e-6)
        np.testing.assert_allclose(sensor[3, 5], [-1 + 3.5 / 4, -1 + 5.5 / 4, 0], atol=1e-6)


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--tpb', default=TPB)
    args, rest = ap.parse_known_args()
    TPB = os.path.abspath(args.tpb)
    unittest.main(argv=[sys.argv[0]] + rest)
