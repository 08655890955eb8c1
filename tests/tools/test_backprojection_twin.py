#!/usr/bin/env python3
"""`tpb render --backproject` (render/nlos_backprojection.h) and tools/nlos_backproject agree on the
same capture.h5: same grid, volumes equal to float32 rounding, same peak voxel. Run on a confocal,
a single-laser and an exhaustive scan, timed from the wall and from the devices, without and with the
Laplacian filter. Also: --backproject on a camera without a scan, and --bp-* without --backproject,
are refused naming the flag.

Run: python3 tests/tools/test_backprojection_twin.py --tpb build/tpb   (CTest: backprojection_twin)
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import unittest

try:
    import numpy as np
    import h5py  # noqa: F401 (the tool reads capture.h5 with it)
except ImportError:  # pragma: no cover - depends on the machine
    if os.path.realpath(sys.executable) != os.path.realpath('/usr/bin/python3') \
            and os.path.exists('/usr/bin/python3'):
        os.execv('/usr/bin/python3', ['/usr/bin/python3', os.path.abspath(__file__)] + sys.argv[1:])
    sys.exit('test_backprojection_twin: needs numpy and h5py (apt-get install python3-numpy python3-h5py)')

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TPB = os.path.join(ROOT, 'build', 'tpb')


def scene(scan, origin):
    """The T-less square target of test_nlos_capture.py, 6 x 6 wall points, one cheap pass."""
    return {
        "version": 1,
        "camera": {"type": "relay_wall", "position": [-0.5, 0, 0.25], "wall": "relay", "resolution": [6, 6],
                   "time_origin": origin, "scan": scan},
        "film": {"start_m": 0.5 if origin == "wall" else 2.5, "bin_width_m": 0.02, "bins": 200},
        "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
        "shapes": [{"name": "relay", "type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0],
                    "edge_v": [0, 2, 0], "material": "white"},
                   {"name": "target", "type": "quad", "corner": [-0.25, -0.25, 1.0], "edge_u": [0, 0.5, 0],
                    "edge_v": [0.5, 0, 0], "material": "white"}],
        "lights": [{"name": "laser", "type": "laser", "position": [-0.5, 0, 0.25], "power": 1}],
        "render": {"photons_per_pass": 5000, "surface_radius": 0.08, "radius": 0.01, "max_depth": 4,
                   "seed": 3, "passes": 1},
    }


class Twin(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_tpb(self, name, doc, extra):
        path = os.path.join(self.tmp.name, name + '.json')
        with open(path, 'w') as f:
            json.dump(doc, f)
        out = os.path.join(self.tmp.name, name)
        return out, subprocess.run([TPB, 'render', path, '-o', out, '--no-frames', '--quiet', '--strip', '0'] + extra,
                                   capture_output=True, text=True)

    def test_same_volume_as_the_python_tool(self):
        scans = {'confocal': {"mode": "confocal", "laser": "laser"},
                 'single': {"mode": "single", "laser": "laser", "point": [0.4, 0.6]},
                 'exhaustive': {"mode": "exhaustive", "laser": "laser", "grid": [2, 2]}}
        for kind, scan in scans.items():
            for origin in ('wall', 'sensor'):
                for filt, grid in (('none', []), ('laplacian', ['--bp-depth-min', '0.4', '--bp-depth-max', '1.6',
                                                                '--bp-depths', '25'])):
                    with self.subTest(scan=kind, origin=origin, filter=filt):
                        out, r = self.run_tpb(f'{kind}_{origin}_{filt}', scene(scan, origin),
                                              ['--backproject', '--bp-filter', filt] + grid)
                        self.assertEqual(r.returncode, 0, r.stderr)
                        py_npy = os.path.join(out, 'python.npy')
                        p = subprocess.run([sys.executable, os.path.join(ROOT, 'tools', 'nlos_backproject'),
                                            os.path.join(out, 'capture.h5'), '--out', py_npy, '--filter', filt] +
                                           [a.replace('--bp-depths', '--voxels').replace('--bp-', '--')
                                            for a in grid], capture_output=True, text=True)
                        self.assertEqual(p.returncode, 0, p.stderr)
                        ours = np.load(os.path.join(out, 'backprojection.npy'))
                        theirs = np.load(py_npy)
                        self.assertEqual(ours.shape, theirs.shape)
                        scale = float(np.abs(theirs).max())
                        self.assertGreater(scale, 0.0)
                        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-5 * scale)
                        with open(os.path.join(out, 'backprojection.json')) as f:
                            meta = json.load(f)
                        summary = json.loads(p.stdout)
                        self.assertEqual(meta['peak']['voxel'], summary['max_voxel'])
                        self.assertAlmostEqual(meta['depths_m'][0], summary['depth_range_m'][0], places=5)
                        self.assertAlmostEqual(meta['depths_m'][-1], summary['depth_range_m'][1], places=5)
                        with open(os.path.join(out, 'summary.json')) as f:
                            kept = json.load(f)['outputs']['files']
                        self.assertIn('backprojection.npy', kept)

    def test_refusals_name_the_flag(self):
        doc = scene({"mode": "confocal", "laser": "laser"}, 'wall')
        pinhole = dict(doc)
        pinhole['camera'] = {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40, "resolution": [8, 8]}
        _, r = self.run_tpb('pinhole', pinhole, ['--backproject'])
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn('--backproject', r.stderr)
        self.assertIn('"scan"', r.stderr)
        _, r = self.run_tpb('no_flag', doc, ['--bp-depths', '8'])
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn('add --backproject', r.stderr)
        _, r = self.run_tpb('zero', doc, ['--backproject', '--bp-depth-max', '0'])
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn('--bp-depth-max', r.stderr)
        _, r = self.run_tpb('inverted', doc, ['--backproject', '--bp-depth-min', '2', '--bp-depth-max', '1'])
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn('must be beyond --bp-depth-min', r.stderr)
        _, r = self.run_tpb('huge', doc, ['--backproject', '--bp-depths', '100000'])
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn('--bp-depths', r.stderr)


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--tpb', default=TPB)
    args, rest = ap.parse_known_args()
    TPB = os.path.abspath(args.tpb)
    unittest.main(argv=[sys.argv[0]] + rest)
