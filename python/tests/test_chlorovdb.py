"""Tests of the chlorovdb Python module (run by CTest as `python_bindings`).

Run by hand from a build with -DCHLOROVDB_PYTHON=ON:
    PYTHONPATH=build-robust/python CHLOROVDB_SPECTRA=$PWD/spectra \
        /usr/bin/python3 -m unittest -v python/tests/test_chlorovdb.py
"""
import json
import math
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import unittest

import numpy as np

import chlorovdb

SOURCE_DIR = pathlib.Path(os.environ.get("CHLOROVDB_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))

# A sphere of dye (absorbs UV/blue and its red band, emits near 680 nm) on a floor,
# under a white environment and a UV distant light.
DYE_SCENE = {
    "render": {"resolution": [8, 6], "spp": 2, "wavelengths": 4, "fluorescence": "full"},
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.3, 0], "fov": 35},
    "pigments": {"dye": {"extinction": {"table": {"lambda": [250, 480, 481, 640, 660, 700, 701],
                                                  "value": [3e4, 3e4, 0, 0, 8e4, 0, 0]}},
                         "quantum_yield": 0.6, "emission": {"gaussian": [680, 12]}}},
    "materials": {"boundary": {"type": "interface"}, "floor": {"type": "diffuse", "albedo": 0.7}},
    "media": {"dye": {"solvent": "water", "pigments": [{"pigment": "dye", "concentration": 20}]}},
    "shapes": [{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "boundary", "inside": "dye"},
               {"type": "quad", "corner": [-3, 0, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0],
                "material": "floor"}],
    "lights": [{"type": "environment", "spectrum": "D65", "scale": 0.01},
               {"type": "distant", "direction": [0, -1, 0], "spectrum": {"gaussian": [320, 15]}, "scale": 1}],
}


def unit_cube_mesh(size):
    v = np.array([[x, y, z] for z in (0, size) for y in (0, size) for x in (0, size)], dtype=np.float32)
    # Outward-facing triangles of the 8-corner cube (index = x + 2 y + 4 z).
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, c, d in quads:
        tris += [(a, b, c), (a, c, d)]
    return v, np.array(tris, dtype=np.int64)


class ChlorovdbTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="chlorovdb_python_test_")
        cls.dir = pathlib.Path(cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def write_scene(self, name, scene):
        path = self.dir / f"{name}.json"
        path.write_text(json.dumps(scene))
        return path

    def test_module_basics(self):
        self.assertTrue(chlorovdb.__version__)
        self.assertIn("D65", chlorovdb.spectrum_names())
        self.assertTrue(issubclass(chlorovdb.InputError, ValueError))

    def test_load_scene_with_overrides(self):
        scene = chlorovdb.load_scene(SOURCE_DIR / "scenes" / "default.json", width=16, height=12, spp=3,
                                     wavelengths=4, seed=9, fluorescence="direct")
        self.assertEqual((scene.width, scene.height, scene.spp, scene.wavelengths, scene.seed), (16, 12, 3, 4, 9))
        self.assertEqual(scene.fluorescence, "direct")
        self.assertTrue(scene.has_fluorescence)
        self.assertIn("solution", scene.media)

    def test_input_errors_name_file_key_and_value(self):
        bad = dict(DYE_SCENE)
        bad["camera"] = {"position": [0, 0, 4], "look_at": [0, 0, 0], "fvo": 30}
        path = self.write_scene("bad_key", bad)
        with self.assertRaises(chlorovdb.InputError) as ctx:
            chlorovdb.load_scene(path)
        message = str(ctx.exception)
        self.assertIn("bad_key.json", message)
        self.assertIn("camera.fvo", message)
        self.assertIn("fov", message)  # the "did you mean"
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.load_scene(path.with_name("missing.json"))
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.load_scene(self.write_scene("ok", DYE_SCENE), fluorescence="fulll")
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.load_scene(self.write_scene("ok", DYE_SCENE), spp=0)

    def test_edit_a_scene_as_a_document_and_render_it(self):
        path = self.write_scene("doc", DYE_SCENE)
        scene = chlorovdb.load(path, set={"media.dye.pigments[0].concentration": 10, "render.spp": 2})
        self.assertEqual(scene.media["dye"].pigments[0].concentration, 10)
        self.assertEqual(scene.render.spp, 2)
        scene.media["dye"].pigments[0].concentration = 5
        self.assertEqual(scene.media["dye"].pigments[0]["concentration"], 5)
        edited = chlorovdb.render(scene, threads=1, seed=4)

        # The same edit written to a file renders the same image: one loader, one session.
        changed = json.loads(json.dumps(DYE_SCENE))
        changed["media"]["dye"]["pigments"][0]["concentration"] = 5
        from_file = chlorovdb.render(chlorovdb.load_scene(self.write_scene("doc5", changed)), threads=1, seed=4)
        for name in from_file.layers:
            np.testing.assert_array_equal(edited[name], from_file[name], name)
        # ... and differs from the unedited scene.
        original = chlorovdb.render(chlorovdb.load_scene(path), threads=1, seed=4)
        self.assertFalse(np.array_equal(original["fluorescence"], edited["fluorescence"]))
        self.assertEqual(scene.to_python()["media"]["dye"]["pigments"][0]["concentration"], 5)

        # A bad edit is refused by the loader with the key named, at render as at check().
        scene.camera.fov = "wide"
        with self.assertRaises(chlorovdb.InputError) as ctx:
            chlorovdb.render(scene)
        self.assertIn("camera.fov", str(ctx.exception))
        with self.assertRaises(chlorovdb.InputError):
            scene.check()
        with self.assertRaises(chlorovdb.InputError) as ctx:
            chlorovdb.load(path, set={"shapes[7].radius": 1})
        self.assertIn("no element 7", str(ctx.exception))
        with self.assertRaises(AttributeError):
            scene.no_such_key

    def test_document_paths_resolve_against_the_scene_folder(self):
        folder = pathlib.Path(self.tmp.name) / "sub"
        folder.mkdir()
        (folder / "floor.obj").write_text("v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 4 3\nf 1 3 2\n")
        scene = json.loads(json.dumps(DYE_SCENE))
        scene["shapes"][1] = {"type": "mesh", "file": "floor.obj", "material": "floor"}
        path = folder / "mesh.json"
        path.write_text(json.dumps(scene))
        cwd = os.getcwd()
        os.chdir(self.tmp.name)
        try:
            doc = chlorovdb.load("sub/mesh.json", set={"render.resolution": [4, 3]})
            result = chlorovdb.render(doc, spp=1, threads=1)
        finally:
            os.chdir(cwd)
        self.assertEqual(result["total"].shape, (3, 4, 3))

    def test_render_checkpoint_resumes_to_the_uninterrupted_image(self):
        scene = chlorovdb.load(self.write_scene("ckpt", DYE_SCENE))
        ckpt = pathlib.Path(self.tmp.name) / "dye.ckpt"
        first = chlorovdb.render(scene, spp=3, threads=1, seed=2, checkpoint=ckpt)
        self.assertEqual(first.samples_per_pixel, 3)
        self.assertTrue(ckpt.exists())
        with self.assertRaises(chlorovdb.InputError):  # an existing checkpoint without resume=True
            chlorovdb.render(scene, spp=3, threads=1, seed=2, checkpoint=ckpt)
        # The session's checkpoint refuses another scene.
        scene.media["dye"].pigments[0].concentration = 1
        with self.assertRaises(chlorovdb.InputError) as ctx:
            chlorovdb.render(scene, spp=6, threads=1, seed=2, checkpoint=ckpt, resume=True)
        self.assertIn("scene_hash", str(ctx.exception))
        scene.media["dye"].pigments[0].concentration = 20
        resumed = chlorovdb.render(scene, spp=6, threads=1, seed=2, checkpoint=ckpt, resume=True)
        whole = chlorovdb.render(scene, spp=6, threads=1, seed=2)
        self.assertEqual(resumed.metadata["resumed_at_spp"], 3)
        for name in whole.layers:
            np.testing.assert_array_equal(resumed[name], whole[name], name)

    def test_ctrl_c_raises_keyboard_interrupt_carrying_the_finished_passes(self):
        # A child process renders far more samples than it will finish; SIGINT (what
        # Ctrl-C sends) once it is rendering stops it at the end of the current pass.
        scene_path = self.write_scene("interrupt", DYE_SCENE)
        ckpt = self.dir / "interrupt.ckpt"
        child = textwrap.dedent(f"""
            import json, sys
            import numpy as np
            import chlorovdb
            scene = chlorovdb.load({str(scene_path)!r})
            print("rendering", flush=True)
            try:
                chlorovdb.render(scene, spp=1 << 22, threads=1, seed=5, checkpoint={str(ckpt)!r})
                print(json.dumps({{"returned": True}}))
            except KeyboardInterrupt as e:
                r = e.result
                print(json.dumps({{"message": str(e), "spp": r.samples_per_pixel, "meta_spp": r.metadata["spp"],
                                  "interrupted": r.metadata["interrupted"], "shape": list(r["total"].shape),
                                  "finite": bool(np.all(np.isfinite(r["total"]))), "mean": float(r["total"].mean())}}))
        """)
        proc = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            self.assertEqual(proc.stdout.readline().strip(), "rendering")
            time.sleep(1.0)  # into the render (a pass of 8x6 pixels takes well under a millisecond)
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
        self.assertEqual(proc.returncode, 0, err)
        report = json.loads(out.strip().splitlines()[-1])
        self.assertNotIn("returned", report, "the render ran to the end instead of stopping")
        self.assertGreater(report["spp"], 0)
        self.assertLess(report["spp"], 1 << 22)
        self.assertEqual(report["meta_spp"], report["spp"])
        self.assertEqual(report["interrupted"], 1)
        self.assertEqual(report["shape"], [6, 8, 3])
        self.assertTrue(report["finite"])
        self.assertGreater(report["mean"], 0)
        self.assertIn(f"after {report['spp']} of {1 << 22}", report["message"])
        # The checkpoint holds the same passes, so the render can resume.
        scene = chlorovdb.load(scene_path)
        resumed = chlorovdb.render(scene, spp=report["spp"] + 1, threads=1, seed=5, checkpoint=ckpt, resume=True)
        self.assertEqual(resumed.metadata["resumed_at_spp"], report["spp"])

    def test_aovs_are_returned_as_arrays(self):
        scene = chlorovdb.load(self.write_scene("aovs", DYE_SCENE), set={"render.aovs": ["alpha", "depth", "normal", "albedo"]})
        result = chlorovdb.render(scene, spp=2, threads=1, seed=3)
        self.assertEqual(result["alpha"].shape, (6, 8, 1))
        self.assertEqual(result["depth"].shape, (6, 8, 2))  # Z, coverage
        self.assertEqual(result["N"].shape, (6, 8, 3))
        self.assertEqual(result["albedo"].shape, (6, 8, 3))
        self.assertEqual(result.metadata["aovs"], "alpha,depth,normal,albedo")
        # Pixels wholly on the floor (seen directly or through the dye's interface sphere) are opaque;
        # the sky above it, where no sample hits a surface, has no depth.
        coverage = result["depth"][..., 1]
        self.assertTrue(np.any(coverage == 1) and np.any(coverage == 0))
        np.testing.assert_array_equal(result["alpha"][coverage == 1], 1.0)
        self.assertTrue(np.all(np.isfinite(result["depth"][..., 0][coverage > 0])))
        self.assertTrue(np.all(np.isinf(result["depth"][..., 0][coverage == 0])))
        self.assertNotIn("alpha", chlorovdb.render(chlorovdb.load(self.write_scene("plain", DYE_SCENE)), spp=1).layers)
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.load(self.write_scene("bad_aovs", DYE_SCENE), set={"render.aovs": ["alfa"]})

    def test_render_layers_are_float32_hxwx3_and_add_up(self):
        scene = chlorovdb.load_scene(self.write_scene("dye", DYE_SCENE))
        result = chlorovdb.render(scene, spp=4, threads=1, seed=3)
        means = {"total", "fluorescence", "nonfluorescence"}
        self.assertEqual(set(result.layers), means | {m + "_stderr" for m in means})
        for name, image in result.layers.items():
            self.assertEqual(image.shape, (6, 8, 3), name)
            self.assertEqual(image.dtype, np.float32, name)
            self.assertTrue(np.all(np.isfinite(image)), name)
        for m in means:  # the standard error of each pixel's mean: never negative, zero where the mean is
            err = result[m + "_stderr"]
            self.assertTrue(np.all(err >= 0), m)
            self.assertTrue(np.all(err[result[m] == 0] == 0), m)
        total, fl, other = result["total"], result["fluorescence"], result["nonfluorescence"]
        np.testing.assert_allclose(total, fl + other, rtol=1e-4, atol=1e-7)
        self.assertGreater(float(fl.sum()), 0.0)
        self.assertEqual(result.samples_per_pixel, 4)
        self.assertEqual(result.nonfinite_samples, 0)
        self.assertGreaterEqual(result.paths, 6 * 8 * 4)  # camera paths plus excitation continuations
        routes = result.excitation_routes
        self.assertGreater(routes["connection"]["sum"], 0.0)
        self.assertGreater(routes["events"], 0)
        for name in ("connection", "bounce", "continuation_light", "continuation_reemitted", "photons"):
            self.assertLessEqual(routes[name]["events"], routes["events"], name)
            self.assertGreaterEqual(routes[name]["sum_squares"], 0.0, name)
        self.assertIsNone(result.spectral)
        self.assertEqual(result.metadata["nonfinite_samples"], 0)

    def test_render_is_deterministic_across_thread_counts(self):
        scene = chlorovdb.load_scene(self.write_scene("dye", DYE_SCENE))
        one = chlorovdb.render(scene, spp=3, threads=1, seed=5)
        two = chlorovdb.render(scene, spp=3, threads=2, seed=5)
        for name in one.layers:
            np.testing.assert_array_equal(one[name], two[name])
        other_seed = chlorovdb.render(scene, spp=3, threads=1, seed=6)
        self.assertFalse(np.array_equal(one["total"], other_seed["total"]))

    def test_spectral_bins_give_per_pixel_spectra(self):
        # Camera looking at an empty white furnace: spectral radiance 1 in every bin.
        furnace = {"render": {"resolution": [6, 4], "wavelengths": 8},
                   "camera": {"position": [0, 0, 1], "look_at": [0, 0, 0]},
                   "lights": [{"type": "environment", "spectrum": 1}]}
        scene = chlorovdb.load_scene(self.write_scene("furnace", furnace))
        result = chlorovdb.render(scene, spp=64, threads=1, spectral_bins=10)
        spectral = result.spectral
        self.assertEqual(spectral.shape, (4, 6, 10))
        self.assertEqual(spectral.dtype, np.float32)
        self.assertEqual(result.wavelengths_nm.shape, (10,))
        self.assertAlmostEqual(result.bin_width_nm, 47.0, places=4)
        self.assertAlmostEqual(float(result.wavelengths_nm[0]), 360 + 23.5, places=3)
        self.assertTrue(np.all(np.isfinite(spectral)))
        self.assertAlmostEqual(float(spectral.mean()), 1.0, delta=0.05)
        np.testing.assert_allclose(spectral.mean(axis=(0, 1)), np.ones(10), rtol=0.3)
        # Spectra of the dye scene: fluorescence puts energy near 680 nm.
        dye = chlorovdb.render(chlorovdb.load_scene(self.write_scene("dye", DYE_SCENE)), spp=2, spectral_bins=47)
        self.assertEqual(dye.spectral.shape, (6, 8, 47))
        self.assertTrue(np.all(np.isfinite(dye.spectral)))

    def test_grid_round_trip_and_render(self):
        rng = np.random.default_rng(1)
        values = rng.uniform(0.5, 2.0, size=(5, 4, 3)).astype(np.float32)  # [z, y, x]
        path = self.dir / "blob.vdb"
        chlorovdb.write_grid(path, values, voxel_size=0.05, origin=(2, -3, 4), unit="uM", provenance="test")
        read, lo, world_from_index, meta = chlorovdb.read_grid(path)
        # The stored box is whole 8^3 leaves around the voxels written; the rest is background.
        self.assertTrue(all(l <= o and l % 8 == 0 for l, o in zip(lo, (2, -3, 4))), lo)
        x0, y0, z0 = 2 - lo[0], -3 - lo[1], 4 - lo[2]
        np.testing.assert_array_equal(read[z0:z0 + 5, y0:y0 + 4, x0:x0 + 3], values)
        self.assertAlmostEqual(float(read.sum()), float(values.sum()), places=2)
        self.assertAlmostEqual(float(world_from_index[0, 0]), 0.05, places=6)
        self.assertEqual(meta["unit"], "uM")
        self.assertEqual(meta["provenance"], "test")
        scene = {"render": {"resolution": [6, 6], "wavelengths": 4},
                 "camera": {"position": [0.2, 0.0, 2.0], "look_at": [0.2, -0.05, 0.3]},
                 "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.3}},
                 "media": {"blob": {"pigments": [{"pigment": "chl", "grid": {"file": "blob.vdb", "scale": 100}}]}},
                 "lights": [{"type": "environment", "spectrum": "D65", "scale": 0.01},
                            {"type": "distant", "direction": [0, 0, -1], "spectrum": "UVB", "scale": 1}]}
        result = chlorovdb.render(chlorovdb.load_scene(self.write_scene("grid", scene)), spp=4, threads=1)
        self.assertTrue(np.all(np.isfinite(result["total"])))
        self.assertEqual(result.nonfinite_samples, 0)
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.read_grid(path, "nope")
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.write_grid(self.dir / "bad.vdb", values, voxel_size=-1.0)

    @unittest.skipUnless(getattr(chlorovdb, "HAVE_VOXELIZE", False), "built without src/voxelize")
    def test_voxelize_mesh_fills_the_cube(self):
        vertices, triangles = unit_cube_mesh(0.01)  # 1 cm cube
        out = self.dir / "cube.vdb"
        report = chlorovdb.voxelize_mesh(vertices, triangles, out, voxel_size=0.001, concentration=5.0, unit="uM")
        self.assertAlmostEqual(report["filled_volume_m3"], 1e-6, delta=0.02e-6)
        self.assertGreater(report["active_voxels"], 900)
        values, lo, world_from_index, meta = chlorovdb.read_grid(out)
        self.assertEqual(meta["unit"], "uM")
        self.assertAlmostEqual(float(values.max()), 5.0, places=4)
        self.assertAlmostEqual(float(values.sum()) * 1e-9, 5.0 * 1e-6, delta=0.1e-6)
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.voxelize_mesh(vertices, triangles, self.dir / "x.vdb", voxel_size=0.001, mode="bogus")
        with self.assertRaises(chlorovdb.InputError):
            chlorovdb.voxelize_mesh(vertices, triangles + 100, self.dir / "x.vdb", voxel_size=0.001)
        with self.assertRaises(chlorovdb.InputError):  # the memory estimate refuses 1e18 voxels
            chlorovdb.voxelize_mesh(vertices * 100, triangles, self.dir / "x.vdb", voxel_size=1e-6)


if __name__ == "__main__":
    unittest.main()
