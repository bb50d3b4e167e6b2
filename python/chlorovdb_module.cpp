// Python bindings (docs/python.md): load a scene (read-only, or as an editable
// document of its JSON that re-validates through the same loader), render it
// through the render session the CLI uses, get NumPy arrays of every film layer
// (H x W x 3, float32) and of per-pixel spectra (H x W x bins), write and read
// concentration grids, voxelize meshes.
//
// Errors: chlorovdb.InputError (a ValueError) for bad input, carrying the
// library's message (file, key, value, problem). Renders release the GIL and
// honour Ctrl-C between passes (a checkpoint, when asked for, is written with
// the completed passes, then KeyboardInterrupt is raised).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "checkpoint/partition.h"
#include "core/error.h"
#include "grids/vdb_file.h"
#include "integrator/render.h"
#include "scene/param_reader.h"
#include "scene/scene_loader.h"
#include "session/render_session.h"
#include "spectra/library.h"
#ifdef CHLOROVDB_HAVE_VOXELIZE
#include "geometry/mesh.h"
#include "voxelize/voxelize.h"
#endif

namespace py = pybind11;
using namespace chlorovdb;

namespace {

// A copy of interleaved floats as a C-contiguous float32 array of `shape`.
py::array_t<float> to_array(const std::vector<float>& values, std::vector<py::ssize_t> shape) {
  py::array_t<float> a(shape);
  std::memcpy(a.mutable_data(), values.data(), values.size() * sizeof(float));
  return a;
}

py::object metadata_value(const MetadataValue& v) {
  return std::visit([](const auto& x) -> py::object { return py::cast(x); }, v);
}

struct RenderResult {
  int width = 0, height = 0;
  py::dict layers;     // name -> H x W x 3
  py::object spectral = py::none();  // H x W x bins, or None
  py::object wavelengths_nm = py::none();  // bin centres
  double bin_width_nm = 0;
  int samples_per_pixel = 0;
  double seconds = 0;
  uint64_t nonfinite_samples = 0;
  PathStats paths;
  py::dict metadata;
};

// A scene file's JSON held for editing: `scene.media["solution"].pigments[0].concentration = 5`.
// Every render (and check()) loads it through load_scene, so an edit is validated
// exactly as the same key in a file, and relative paths resolve against `file`'s folder.
// One object or array inside a document (shares the document's JSON).
struct SceneNode {
  std::shared_ptr<nlohmann::json> root;
  nlohmann::json::json_pointer at;
  nlohmann::json& value() const { return root->at(at); }
};

struct SceneDocument {
  std::shared_ptr<nlohmann::json> json;
  std::filesystem::path file;
  SceneOverrides overrides;
  Scene load() const { return load_scene(*json, file, overrides); }
  SceneNode top() const { return SceneNode{json, nlohmann::json::json_pointer()}; }
};

nlohmann::json to_json(py::handle o) {
  if (o.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(o)) return o.cast<bool>();
  if (py::isinstance<py::int_>(o)) return o.cast<int64_t>();
  if (py::isinstance<py::float_>(o)) return o.cast<double>();
  if (py::isinstance<py::str>(o)) return o.cast<std::string>();
  if (py::isinstance<SceneNode>(o)) return o.cast<const SceneNode&>().value();
  if (py::isinstance<py::dict>(o)) {
    nlohmann::json j = nlohmann::json::object();
    for (auto [k, v] : o.cast<py::dict>()) j[py::str(k).cast<std::string>()] = to_json(v);
    return j;
  }
  if (py::isinstance<py::array>(o)) return to_json(o.attr("tolist")());
  if (py::isinstance<py::list>(o) || py::isinstance<py::tuple>(o)) {
    nlohmann::json j = nlohmann::json::array();
    for (py::handle v : o) j.push_back(to_json(v));
    return j;
  }
  if (py::hasattr(o, "item")) return to_json(o.attr("item")());  // NumPy scalars
  throw InputError("python", "value", py::repr(o).cast<std::string>(), "cannot be stored in a scene (use numbers, strings, lists, dicts)");
}

// Plain Python values for leaves, nodes for objects and arrays (so edits chain).
py::object from_json(const SceneNode& parent, const nlohmann::json::json_pointer& at) {
  const nlohmann::json& j = parent.root->at(at);
  if (j.is_object() || j.is_array()) return py::cast(SceneNode{parent.root, at});
  if (j.is_null()) return py::none();
  if (j.is_boolean()) return py::bool_(j.get<bool>());
  if (j.is_number_integer()) return py::int_(j.get<int64_t>());
  if (j.is_number()) return py::float_(j.get<double>());
  return py::str(j.get<std::string>());
}

py::object plain(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

nlohmann::json::json_pointer child(const SceneNode& n, py::handle key) {
  const nlohmann::json& v = n.value();
  if (v.is_array()) {
    if (!py::isinstance<py::int_>(key)) throw py::type_error("a scene array is indexed by integers");
    int64_t i = key.cast<int64_t>();
    if (i < 0) i += int64_t(v.size());
    if (i < 0 || i >= int64_t(v.size())) throw py::index_error("scene array index out of range");
    return n.at / size_t(i);
  }
  return n.at / py::str(key).cast<std::string>();
}

py::object node_get(const SceneNode& n, py::handle key) {
  const auto at = child(n, key);
  if (n.value().is_object() && !n.value().contains(at.back())) throw py::key_error(py::str(key).cast<std::string>());
  return from_json(n, at);
}

void node_set(const SceneNode& n, py::handle key, py::handle value) {
  if (!n.value().is_object() && !n.value().is_array()) throw py::type_error("not an object or array");
  n.root->operator[](child(n, key)) = to_json(value);
}

RenderResult render_scene(const Scene& scene, const std::string& scene_hash, std::optional<int> spp, int threads,
                          std::optional<uint64_t> seed, std::optional<int> spectral_bins, int first_sample,
                          std::optional<std::string> color_space, std::optional<std::filesystem::path> checkpoint,
                          bool resume, double checkpoint_every) {
  const RenderSettings& s = scene.settings;
  RenderJob job;
  if (color_space) {
    if (*color_space == "srgb") job.color_space = ColorSpace::sRGB;
    else if (*color_space == "acescg") job.color_space = ColorSpace::ACEScg;
    else throw InputError("render()", "color_space", *color_space, "must be \"srgb\" or \"acescg\"");
  }
  const int bins = spectral_bins.value_or(s.spectral_bins);
  if (bins < 0 || bins > 4096) throw InputError("render()", "spectral_bins", std::to_string(bins), "must be in [0, 4096]");
  if (threads < 0) throw InputError("render()", "threads", std::to_string(threads), "must be >= 0 (0: all cores)");
  if (first_sample < 0) throw InputError("render()", "first_sample", std::to_string(first_sample), "must be >= 0");
  const int n = spp.value_or(s.spp);
  if (n < 1) throw InputError("render()", "spp", std::to_string(n), "must be >= 1");
  if (!(checkpoint_every >= 0)) throw InputError("render()", "checkpoint_every", std::to_string(checkpoint_every), "must be >= 0");
  job.samples = SampleRange{first_sample, first_sample + n};
  job.spectral_bins = bins;
  job.threads = threads;
  job.seed = seed;
  job.scene_hash = scene_hash;
  if (checkpoint) job.checkpoint = *checkpoint;
  job.resume = resume;
  job.checkpoint_every = checkpoint_every;
  // Between passes: give Python a chance to see Ctrl-C.
  job.poll_interrupt = [] {
    py::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  };
  std::optional<RenderOutcome> outcome;
  {
    py::gil_scoped_release release;
    outcome = run_render_session(scene, job);
  }
  // Ctrl-C: PyErr_CheckSignals ran Python's handler, whose exception is pending.
  // Take it out (the result needs the interpreter), build what the finished
  // passes hold and raise KeyboardInterrupt carrying it as `.result`; a signal
  // handler that raised anything else, or no finished pass, re-raises as is.
  std::optional<py::error_already_set> pending;
  if (outcome->interrupted && PyErr_Occurred()) pending.emplace();
  if (pending && (!pending->matches(PyExc_KeyboardInterrupt) || outcome->samples_done == 0)) throw std::move(*pending);
  if (outcome->samples_done == 0) throw std::runtime_error("render: no pass completed");

  const Image image = session_image(scene, job, *outcome);
  RenderResult r;
  r.width = image.width;
  r.height = image.height;
  for (const ImageLayer& layer : image.layers) {
    const auto c = py::ssize_t(layer.channels.size());
    if (layer.name == "S0") {
      r.spectral = to_array(layer.pixels, {image.height, image.width, c});
      py::array_t<float> centres(c);
      const double width_nm = (double(kLambdaMax) - kLambdaMin) / bins;
      for (py::ssize_t b = 0; b < c; ++b) centres.mutable_at(b) = float(kLambdaMin + (b + 0.5) * width_nm);
      r.wavelengths_nm = centres;
      r.bin_width_nm = width_nm;
    } else {
      r.layers[py::str(layer.name)] = to_array(layer.pixels, {image.height, image.width, c});
    }
  }
  r.samples_per_pixel = outcome->samples_done;
  r.seconds = outcome->session_seconds;
  r.nonfinite_samples = outcome->nonfinite_samples;
  r.paths = outcome->paths;
  for (const auto& [key, value] : image.metadata.entries) r.metadata[py::str(key)] = metadata_value(value);
  r.metadata["seed"] = job_seed(scene, job);
  if (pending) {
    py::object interrupt = py::reinterpret_borrow<py::object>(PyExc_KeyboardInterrupt)(fmt::format(
        "render interrupted after {} of {} samples per pixel; the exception's .result holds them", r.samples_per_pixel,
        outcome->range.size()));
    interrupt.attr("result") = py::cast(std::move(r));
    PyErr_SetObject(PyExc_KeyboardInterrupt, interrupt.ptr());
    throw py::error_already_set();
  }
  return r;
}

SceneOverrides overrides_from(std::optional<int> width, std::optional<int> height, std::optional<int> spp,
                              std::optional<int> wavelengths, std::optional<uint64_t> seed,
                              std::optional<std::string> fluorescence, std::optional<std::string> transmittance) {
  SceneOverrides o;
  auto positive = [](const char* key, std::optional<int> v, int hi) {
    if (v && (*v < 1 || *v > hi))
      throw InputError("load_scene()", key, std::to_string(*v), "must be in [1, " + std::to_string(hi) + "]");
  };
  positive("width", width, 65536);
  positive("height", height, 65536);
  positive("spp", spp, 1 << 24);
  positive("wavelengths", wavelengths, kMaxWavelengths);
  o.width = width;
  o.height = height;
  o.spp = spp;
  o.wavelengths = wavelengths;
  o.seed = seed;
  o.fluorescence = fluorescence;
  o.transmittance = transmittance;
  return o;
}

// `set`: {"media.solution.pigments[0].concentration": 5, ...}, applied in order.
SceneDocument load_document(const std::filesystem::path& file, py::object sets, const SceneOverrides& o) {
  SceneDocument d{std::make_shared<nlohmann::json>(ParamReader::parse_file(file)), file, o};
  if (!sets.is_none())
    for (auto [k, v] : sets.cast<py::dict>()) set_scene_key(*d.json, py::str(k).cast<std::string>(), to_json(v), "set=");
  {
    py::gil_scoped_release release;
    d.load();  // validated now, so a bad file or edit fails at load()
  }
  return d;
}

// Dense copy of a grid's stored voxels: values[z][y][x] over [index_lo, index_hi].
py::tuple read_grid(const std::filesystem::path& path, const std::string& name, bool clamp_invalid,
                    int64_t max_voxels) {
  GridLoadOptions options;
  options.clamp_invalid = clamp_invalid;
  const VoxelGrid grid = load_concentration_grid(path, name, options);
  const Coord lo = grid.index_lo(), hi = grid.index_hi();
  py::ssize_t dims[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) dims[a] = hi[a] >= lo[a] ? py::ssize_t(int64_t(hi[a]) - lo[a] + 1) : 0;
  const double count = double(dims[0]) * double(dims[1]) * double(dims[2]);
  if (count > double(max_voxels))
    throw InputError(path.string(), "grid", name,
                     "its stored box has " + std::to_string(int64_t(count)) + " voxels, more than max_voxels = " +
                         std::to_string(max_voxels) + " (pass a larger max_voxels to read it densely)");
  py::array_t<float> values({dims[2], dims[1], dims[0]});
  auto v = values.mutable_unchecked<3>();
  for (py::ssize_t z = 0; z < dims[2]; ++z)
    for (py::ssize_t y = 0; y < dims[1]; ++y)
      for (py::ssize_t x = 0; x < dims[0]; ++x)
        v(z, y, x) = grid.voxel(lo[0] + int(x), lo[1] + int(y), lo[2] + int(z));
  py::array_t<float> m({4, 4});
  const Transform::Mat& wfi = grid.world_from_index().matrix();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m.mutable_at(i, j) = wfi[i][j];
  py::dict meta;
  meta["unit"] = grid.metadata().unit;
  meta["scale"] = grid.metadata().scale;
  meta["provenance"] = grid.metadata().provenance;
  meta["clamped_voxels"] = grid.metadata().clamped_voxels;
  meta["background"] = grid.background();
  return py::make_tuple(values, py::make_tuple(lo[0], lo[1], lo[2]), m, meta);
}

Vec3 voxel_size_from(py::object voxel_size, const char* where) {
  Vec3 h;
  if (py::isinstance<py::float_>(voxel_size) || py::isinstance<py::int_>(voxel_size)) {
    h = Vec3(voxel_size.cast<float>());
  } else {
    const auto v = voxel_size.cast<std::vector<float>>();
    if (v.size() != 3) throw InputError(where, "voxel_size", "", "must be a number or 3 numbers");
    h = Vec3{v[0], v[1], v[2]};
  }
  if (!(h.x > 0.f && h.y > 0.f && h.z > 0.f) || !std::isfinite(h.x) || !std::isfinite(h.y) || !std::isfinite(h.z))
    throw InputError(where, "voxel_size", "", "must be positive and finite");
  return h;
}

Transform transform_from(py::object matrix, py::object voxel_size) {
  if (!matrix.is_none()) {
    const auto m = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(matrix);
    if (!m || m.ndim() != 2 || m.shape(0) != 4 || m.shape(1) != 4)
      throw InputError("write_grid()", "world_from_index", "", "must be a 4 x 4 matrix");
    Transform::Mat r{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) r[i][j] = float(m.at(i, j));
    try {
      return Transform::from_matrix(r);
    } catch (const std::domain_error& e) {
      throw InputError("write_grid()", "world_from_index", "", e.what());
    }
  }
  return Transform::scale(voxel_size_from(voxel_size, "write_grid()"));
}

void write_grid(const std::filesystem::path& path, py::array_t<float, py::array::c_style | py::array::forcecast> values,
                py::object voxel_size, std::array<int, 3> origin, const std::string& name, const std::string& unit,
                float scale, const std::string& provenance, py::object world_from_index) {
  if (values.ndim() != 3) throw InputError("write_grid()", "values", "", "must be a 3-D array indexed [z, y, x]");
  DenseGrid g({int(values.shape(2)), int(values.shape(1)), int(values.shape(0))});
  std::memcpy(g.values.data(), values.data(), g.values.size() * sizeof(float));
  g.origin = origin;
  g.world_from_index = transform_from(world_from_index, voxel_size);
  g.metadata.name = name;
  g.metadata.unit = unit;
  g.metadata.scale = scale;
  g.metadata.provenance = provenance.empty() ? std::string("chlorovdb python write_grid") : provenance;
  write_concentration_grid(path, g);
}

#ifdef CHLOROVDB_HAVE_VOXELIZE
VoxelizeOptions voxelize_options(py::object voxel_size, const std::string& mode, float thickness, float depth,
                                 const std::string& spill_direction, const std::string& unit,
                                 const std::string& grid_name, const std::string& profile, float concentration,
                                 float c0, float c1, int axis, uint64_t seed, float noise_scale,
                                 float noise_amplitude, int noise_octaves, float falloff_length,
                                 const std::string& falloff_shape, const std::filesystem::path& profile_grid,
                                 const std::string& profile_grid_name, int64_t memory_limit_bytes) {
  VoxelizeOptions o;
  if (!parse_voxelize_mode(mode, &o.mode))
    throw InputError("voxelize()", "mode", mode, "must be \"solid\", \"shell\" or \"spill\"");
  o.voxel_size = voxel_size_from(voxel_size, "voxelize()");
  o.thickness = thickness;
  o.depth = depth;
  if (!parse_spill_direction(spill_direction, &o.spill_direction))
    throw InputError("voxelize()", "spill_direction", spill_direction, "must be \"normal\" or \"up\"");
  o.unit = unit;
  o.grid_name = grid_name;
  ConcentrationProfile& p = o.profile;
  if (!parse_profile_kind(profile, &p.kind))
    throw InputError("voxelize()", "profile", profile, "must be uniform, linear, noise, falloff or grid");
  p.concentration = concentration;
  p.c0 = c0;
  p.c1 = c1;
  p.axis = axis;
  p.seed = seed;
  p.noise_scale = noise_scale;
  p.noise_amplitude = noise_amplitude;
  p.noise_octaves = noise_octaves;
  p.falloff_length = falloff_length;
  if (!parse_falloff_shape(falloff_shape, &p.falloff_shape))
    throw InputError("voxelize()", "falloff_shape", falloff_shape, "must be \"decay\" or \"rise\"");
  p.grid_file = profile_grid;
  p.grid_name = profile_grid_name;
  o.memory_limit_bytes = memory_limit_bytes;
  o.command = "chlorovdb python voxelize";
  return o;
}

py::dict report_dict(const VoxelizeReport& r) {
  py::dict d;
  d["active_voxels"] = r.active_voxels;
  d["filled_volume_m3"] = r.filled_volume;
  d["amount"] = r.amount;
  d["min_value"] = r.min_value;
  d["max_value"] = r.max_value;
  d["index_lo"] = py::make_tuple(r.index_lo[0], r.index_lo[1], r.index_lo[2]);
  d["index_hi"] = py::make_tuple(r.index_hi[0], r.index_hi[1], r.index_hi[2]);
  d["unresolved_voxels"] = r.unresolved_voxels;
  d["estimated_voxels"] = r.estimate.voxels();
  d["estimated_bytes"] = r.estimate.bytes;
  d["provenance"] = r.provenance;
  return d;
}

TriangleMesh mesh_from_arrays(py::array_t<float, py::array::c_style | py::array::forcecast> vertices,
                              py::array_t<int64_t, py::array::c_style | py::array::forcecast> triangles) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw InputError("voxelize_mesh()", "vertices", "", "must be an N x 3 array of positions in metres");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3)
    throw InputError("voxelize_mesh()", "triangles", "", "must be an M x 3 array of vertex indices");
  TriangleMesh mesh;
  const auto v = vertices.unchecked<2>();
  for (py::ssize_t i = 0; i < v.shape(0); ++i) mesh.positions.push_back(Vec3{v(i, 0), v(i, 1), v(i, 2)});
  const auto t = triangles.unchecked<2>();
  for (py::ssize_t i = 0; i < t.shape(0); ++i)
    for (int k = 0; k < 3; ++k) {
      const int64_t index = t(i, k);
      if (index < 0 || index >= v.shape(0))
        throw InputError("voxelize_mesh()", "triangles", std::to_string(index),
                         "vertex index out of range [0, " + std::to_string(v.shape(0)) + ")");
      mesh.indices.push_back(uint32_t(index));
    }
  return mesh;
}
#endif

}  // namespace

PYBIND11_MODULE(chlorovdb, m) {
  m.doc() = "chlorovdb: spectral rendering of fluorescent pigments in OpenVDB volumes (docs/python.md)";
  m.attr("__version__") = CHLOROVDB_VERSION;
  m.attr("LAMBDA_MIN_NM") = kLambdaMin;
  m.attr("LAMBDA_MAX_NM") = kLambdaMax;

  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    }
  });

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A loaded scene (read-only)")
      .def_property_readonly("file", [](const Scene& s) { return s.file; })
      .def_property_readonly("width", [](const Scene& s) { return s.settings.width; })
      .def_property_readonly("height", [](const Scene& s) { return s.settings.height; })
      .def_property_readonly("spp", [](const Scene& s) { return s.settings.spp; })
      .def_property_readonly("seed", [](const Scene& s) { return s.settings.seed; })
      .def_property_readonly("wavelengths", [](const Scene& s) { return s.settings.wavelengths; })
      .def_property_readonly("max_depth", [](const Scene& s) { return s.settings.max_depth; })
      .def_property_readonly("spectral_bins", [](const Scene& s) { return s.settings.spectral_bins; })
      .def_property_readonly("color_space",
                             [](const Scene& s) { return s.settings.color_space == ColorSpace::sRGB ? "srgb" : "acescg"; })
      .def_property_readonly("fluorescence", [](const Scene& s) { return to_string(s.settings.fluorescence); })
      .def_property_readonly("fluorescence_reason", [](const Scene& s) { return s.settings.fluorescence_reason; })
      .def_property_readonly("has_fluorescence", &Scene::has_fluorescence)
      .def_property_readonly("media", [](const Scene& s) { return s.medium_names; })
      .def_property_readonly("light_count", [](const Scene& s) { return s.lights.size(); })
      .def("__repr__", [](const Scene& s) {
        return "<chlorovdb.Scene " + s.file.string() + " " + std::to_string(s.settings.width) + "x" +
               std::to_string(s.settings.height) + ", " + std::to_string(s.settings.spp) + " spp>";
      });

  py::class_<RenderResult>(m, "RenderResult", "Film layers as NumPy arrays and the render's statistics")
      .def_readonly("width", &RenderResult::width)
      .def_readonly("height", &RenderResult::height)
      .def_readonly("layers", &RenderResult::layers,
                    "dict: layer name -> float32 array (height, width, channels): the linear RGB layers and their "
                    "_stderr, and the AOVs asked for (alpha: 1 channel, depth: Z and coverage, N: 3, albedo: 3)")
      .def_readonly("spectral", &RenderResult::spectral,
                    "float32 array (height, width, bins): bin-averaged spectral radiance of the total layer, or None")
      .def_readonly("wavelengths_nm", &RenderResult::wavelengths_nm, "bin centres in nm, or None")
      .def_readonly("bin_width_nm", &RenderResult::bin_width_nm)
      .def_readonly("samples_per_pixel", &RenderResult::samples_per_pixel)
      .def_readonly("seconds", &RenderResult::seconds)
      .def_readonly("nonfinite_samples", &RenderResult::nonfinite_samples)
      .def_readonly("metadata", &RenderResult::metadata)
      .def_property_readonly(
          "paths", [](const RenderResult& r) { return r.paths.paths; },
          "paths traced: camera paths plus excitation continuations")
      .def_property_readonly("fluorescence_events", [](const RenderResult& r) { return r.paths.fluorescence_events; })
      .def_property_readonly("excitation_rays", [](const RenderResult& r) { return r.paths.excitation_rays; })
      .def_property_readonly(
          "excitation_routes",
          [](const RenderResult& r) {
            const ExcitationRouteSums& e = r.paths.excitation_routes;
            py::dict routes;
            for (size_t k = 0; k < kExcitationRoutes; ++k)
              routes[kExcitationRouteKeys[k]] =
                  py::dict(py::arg("sum") = e.sum[k], py::arg("sum_squares") = e.sum_squares[k],
                           py::arg("events") = uint64_t(e.events[k]));
            routes["events"] = uint64_t(e.events_any);
            return routes;
          },
          "what excited the fluorescence the camera saw, per route (connection, bounce, continuation_light, "
          "continuation_reemitted, photons): sums over the camera paths' events of their hero-wavelength "
          "contributions, of their squares, and the events each route contributed to; 'events': those any did")
      .def("__getitem__", [](const RenderResult& r, const std::string& layer) -> py::object {
        if (layer == "S0" || layer == "spectral") return r.spectral;
        if (!r.layers.contains(layer)) throw py::key_error(layer);
        return r.layers[py::str(layer)];
      });

  py::class_<SceneNode>(m, "SceneNode",
                                          "An object or array of an editable scene: index (or attribute) to read, assign to edit")
      .def("__getitem__", &node_get)
      .def("__setitem__", &node_set)
      .def("__getattr__",
           [](const SceneNode& n, const std::string& key) {
             if (!n.value().is_object() || !n.value().contains(key)) throw py::attribute_error(key);
             return from_json(n, n.at / key);
           })
      .def("__setattr__", [](const SceneNode& n, const std::string& key, py::object v) { node_set(n, py::str(key), v); })
      .def("__len__", [](const SceneNode& n) { return n.value().size(); })
      .def("__contains__", [](const SceneNode& n, const std::string& key) { return n.value().is_object() && n.value().contains(key); })
      .def("keys", [](const SceneNode& n) {
        std::vector<std::string> keys;
        if (n.value().is_object())
          for (const auto& [k, v] : n.value().items()) keys.push_back(k);
        return keys;
      })
      .def("append", [](const SceneNode& n, py::object v) {
        if (!n.value().is_array()) throw py::type_error("append() needs a scene array");
        n.value().push_back(to_json(v));
      })
      .def("to_python", [](const SceneNode& n) { return plain(n.value()); }, "A plain copy (dicts, lists, numbers, strings)")
      .def("__repr__", [](const SceneNode& n) { return n.value().dump(); });

  py::class_<SceneDocument>(m, "SceneDocument",
                            "A scene file's JSON held for editing; every render re-validates it through the scene loader")
      .def_property_readonly("file", [](const SceneDocument& d) { return d.file; })
      .def("__getitem__", [](const SceneDocument& d, py::object key) { return node_get(d.top(), key); })
      .def("__setitem__", [](const SceneDocument& d, py::object key, py::object v) { node_set(d.top(), key, v); })
      .def("__getattr__",
           [](const SceneDocument& d, const std::string& key) {
             if (!d.json->contains(key)) throw py::attribute_error(key);
             return from_json(d.top(), nlohmann::json::json_pointer() / key);
           })
      .def("__setattr__", [](const SceneDocument& d, const std::string& key, py::object v) {
        node_set(d.top(), py::str(key), v);
      })
      .def("set", [](const SceneDocument& d, const std::string& key, py::object v) { set_scene_key(*d.json, key, to_json(v), "set()"); },
           py::arg("key"), py::arg("value"), "Set a dotted key path, as --set does: set(\"media.solution.pigments[0].concentration\", 5)")
      .def("check", [](const SceneDocument& d) {
        py::gil_scoped_release release;
        return std::make_shared<Scene>(d.load());
      }, "Load the document as it is now (raises InputError naming the key of a bad edit); returns a read-only Scene")
      .def("to_python", [](const SceneDocument& d) { return plain(*d.json); }, "A plain copy of the JSON as dicts and lists")
      .def("copy", [](const SceneDocument& d) {
        return SceneDocument{std::make_shared<nlohmann::json>(*d.json), d.file, d.overrides};
      }, "An independent copy to edit")
      .def("__repr__", [](const SceneDocument& d) { return "<chlorovdb.SceneDocument " + d.file.string() + ">"; });

  m.def(
      "load_scene",
      [](const std::filesystem::path& file, std::optional<int> width, std::optional<int> height, std::optional<int> spp,
         std::optional<int> wavelengths, std::optional<uint64_t> seed, std::optional<std::string> fluorescence,
         std::optional<std::string> transmittance) {
        const SceneOverrides o = overrides_from(width, height, spp, wavelengths, seed, fluorescence, transmittance);
        py::gil_scoped_release release;
        return std::make_shared<Scene>(load_scene(file, o));
      },
      py::arg("path"), py::kw_only(), py::arg("width") = py::none(), py::arg("height") = py::none(),
      py::arg("spp") = py::none(), py::arg("wavelengths") = py::none(), py::arg("seed") = py::none(),
      py::arg("fluorescence") = py::none(), py::arg("transmittance") = py::none(),
      "Load a scene file (docs/scene-format.md) read-only; keyword arguments override its render settings, as the "
      "CLI's options do. Raises chlorovdb.InputError naming file, key and value.");

  m.def(
      "load",
      [](const std::filesystem::path& file, py::object set, std::optional<int> width, std::optional<int> height,
         std::optional<int> spp, std::optional<int> wavelengths, std::optional<uint64_t> seed,
         std::optional<std::string> fluorescence, std::optional<std::string> transmittance) {
        return load_document(file, set, overrides_from(width, height, spp, wavelengths, seed, fluorescence, transmittance));
      },
      py::arg("path"), py::kw_only(), py::arg("set") = py::none(), py::arg("width") = py::none(),
      py::arg("height") = py::none(), py::arg("spp") = py::none(), py::arg("wavelengths") = py::none(),
      py::arg("seed") = py::none(), py::arg("fluorescence") = py::none(), py::arg("transmittance") = py::none(),
      "Load a scene file as an editable SceneDocument: set={\"key.path\": value} applies edits as --set does; "
      "then scene.media[\"solution\"].pigments[0].concentration = 5 edits in place. Validated now and at every render.");

  auto render_doc =
      "Render `scene` (a Scene or a SceneDocument) through the render session the CLI uses; spp/seed/spectral_bins "
      "default to the scene's settings, threads = 0 uses every core. The image depends only on the seed and the sample "
      "range [first_sample, first_sample + spp), not on the thread count. checkpoint=PATH writes the film's exact sums "
      "(also on Ctrl-C); resume=True continues from it.";
  m.def(
      "render",
      [](const Scene& scene, std::optional<int> spp, int threads, std::optional<uint64_t> seed,
         std::optional<int> spectral_bins, int first_sample, std::optional<std::string> color_space,
         std::optional<std::filesystem::path> checkpoint, bool resume, double checkpoint_every) {
        return render_scene(scene, checkpoint ? hash_file(scene.file) : std::string(), spp, threads, seed, spectral_bins,
                            first_sample, color_space, checkpoint, resume, checkpoint_every);
      },
      py::arg("scene"), py::kw_only(), py::arg("spp") = py::none(), py::arg("threads") = 0, py::arg("seed") = py::none(),
      py::arg("spectral_bins") = py::none(), py::arg("first_sample") = 0, py::arg("color_space") = py::none(),
      py::arg("checkpoint") = py::none(), py::arg("resume") = false, py::arg("checkpoint_every") = 300.0, render_doc);
  m.def(
      "render",
      [](const SceneDocument& doc, std::optional<int> spp, int threads, std::optional<uint64_t> seed,
         std::optional<int> spectral_bins, int first_sample, std::optional<std::string> color_space,
         std::optional<std::filesystem::path> checkpoint, bool resume, double checkpoint_every) {
        std::optional<Scene> scene;
        {
          py::gil_scoped_release release;
          scene.emplace(doc.load());
        }
        return render_scene(*scene, hash_text(doc.json->dump()), spp, threads, seed, spectral_bins, first_sample,
                            color_space, checkpoint, resume, checkpoint_every);
      },
      py::arg("scene"), py::kw_only(), py::arg("spp") = py::none(), py::arg("threads") = 0, py::arg("seed") = py::none(),
      py::arg("spectral_bins") = py::none(), py::arg("first_sample") = 0, py::arg("color_space") = py::none(),
      py::arg("checkpoint") = py::none(), py::arg("resume") = false, py::arg("checkpoint_every") = 300.0, render_doc);

  m.def("spectrum_names", &spectrum_names, "Names of the shipped spectral tables");
  m.def("spectra_dir", &spectra_dir, "Folder the shipped spectral tables are read from (env CHLOROVDB_SPECTRA)");

  m.def("write_grid", &write_grid, py::arg("path"), py::arg("values"), py::kw_only(), py::arg("voxel_size") = 1.0,
        py::arg("origin") = std::array<int, 3>{0, 0, 0}, py::arg("name") = "density", py::arg("unit") = "uM",
        py::arg("scale") = 1.f, py::arg("provenance") = "", py::arg("world_from_index") = py::none(),
        "Write a float grid from a 3-D array indexed [z, y, x] (voxel (i, j, k) = values[k, j, i] at index "
        "origin + (i, j, k)); voxel_size in metres (a number or 3), or a 4 x 4 world_from_index matrix.");
  m.def("read_grid", &read_grid, py::arg("path"), py::arg("name") = "density", py::kw_only(),
        py::arg("clamp_invalid") = false, py::arg("max_voxels") = int64_t(1) << 28,
        "Read a float grid: (values[z, y, x] float32 over the stored box -- whole 8^3 leaves around the "
        "active voxels, background elsewhere -- index_lo (x, y, z) of that box, world_from_index 4 x 4, "
        "metadata dict).");

#ifdef CHLOROVDB_HAVE_VOXELIZE
  m.attr("HAVE_VOXELIZE") = true;
  auto voxelize_doc =
      "Voxelize to a .vdb concentration grid (src/voxelize/voxelize.h: modes solid, shell, spill; profiles "
      "uniform, linear, noise, falloff, grid). voxel_size in metres, a number or 3. Returns the report as a dict.";
  m.def(
      "voxelize_mesh",
      [](py::array_t<float, py::array::c_style | py::array::forcecast> vertices,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> triangles,
         const std::filesystem::path& output, py::object voxel_size, const std::string& mode, float thickness,
         float depth, const std::string& spill_direction, const std::string& unit, const std::string& grid_name,
         const std::string& profile, float concentration, float c0, float c1, int axis, uint64_t seed,
         float noise_scale, float noise_amplitude, int noise_octaves, float falloff_length,
         const std::string& falloff_shape, const std::filesystem::path& profile_grid,
         const std::string& profile_grid_name, int64_t memory_limit_bytes) {
        VoxelizeOptions o = voxelize_options(voxel_size, mode, thickness, depth, spill_direction, unit, grid_name,
                                             profile, concentration, c0, c1, axis, seed, noise_scale,
                                             noise_amplitude, noise_octaves, falloff_length, falloff_shape,
                                             profile_grid, profile_grid_name, memory_limit_bytes);
        o.source_name = "python mesh";
        TriangleMesh mesh = mesh_from_arrays(vertices, triangles);
        VoxelizeReport r;
        {
          py::gil_scoped_release release;
          r = voxelize_mesh(mesh, o, output);
        }
        return report_dict(r);
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("output"), py::kw_only(), py::arg("voxel_size"),
      py::arg("mode") = "solid", py::arg("thickness") = 0.f, py::arg("depth") = 0.f,
      py::arg("spill_direction") = "normal", py::arg("unit") = "uM", py::arg("grid_name") = "density",
      py::arg("profile") = "uniform", py::arg("concentration") = 1.f, py::arg("c0") = 0.f, py::arg("c1") = 1.f,
      py::arg("axis") = 1, py::arg("seed") = 1, py::arg("noise_scale") = 0.f, py::arg("noise_amplitude") = 0.5f,
      py::arg("noise_octaves") = 3, py::arg("falloff_length") = 0.f, py::arg("falloff_shape") = "decay",
      py::arg("profile_grid") = std::filesystem::path(), py::arg("profile_grid_name") = "density",
      py::arg("memory_limit_bytes") = 0, voxelize_doc);
  m.def(
      "voxelize_file",
      [](const std::filesystem::path& input, const std::filesystem::path& output, py::object voxel_size,
         const std::string& mode, float thickness, float depth, const std::string& spill_direction,
         const std::string& unit, const std::string& grid_name, const std::string& profile, float concentration,
         float c0, float c1, int axis, uint64_t seed, float noise_scale, float noise_amplitude, int noise_octaves,
         float falloff_length, const std::string& falloff_shape, const std::filesystem::path& profile_grid,
         const std::string& profile_grid_name, int64_t memory_limit_bytes) {
        VoxelizeOptions o = voxelize_options(voxel_size, mode, thickness, depth, spill_direction, unit, grid_name,
                                             profile, concentration, c0, c1, axis, seed, noise_scale,
                                             noise_amplitude, noise_octaves, falloff_length, falloff_shape,
                                             profile_grid, profile_grid_name, memory_limit_bytes);
        VoxelizeReport r;
        {
          py::gil_scoped_release release;
          r = voxelize_file(input, o, output);
        }
        return report_dict(r);
      },
      py::arg("input"), py::arg("output"), py::kw_only(), py::arg("voxel_size"), py::arg("mode") = "solid",
      py::arg("thickness") = 0.f, py::arg("depth") = 0.f, py::arg("spill_direction") = "normal",
      py::arg("unit") = "uM", py::arg("grid_name") = "density", py::arg("profile") = "uniform",
      py::arg("concentration") = 1.f, py::arg("c0") = 0.f, py::arg("c1") = 1.f, py::arg("axis") = 1,
      py::arg("seed") = 1, py::arg("noise_scale") = 0.f, py::arg("noise_amplitude") = 0.5f,
      py::arg("noise_octaves") = 3, py::arg("falloff_length") = 0.f, py::arg("falloff_shape") = "decay",
      py::arg("profile_grid") = std::filesystem::path(), py::arg("profile_grid_name") = "density",
      py::arg("memory_limit_bytes") = 0, voxelize_doc);
#else
  m.attr("HAVE_VOXELIZE") = false;
#endif
}
