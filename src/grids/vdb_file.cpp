// The one translation unit that includes OpenVDB.
#include "grids/vdb_file.h"

#include <fstream>
#include <mutex>

#include <fmt/format.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "core/error.h"

namespace chlorovdb {
namespace {

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Walks the file's header, metadata and grid descriptors (OpenVDB's layout:
// io/Archive.cc, io/GridDescriptor.cc) and refuses a file whose descriptors or
// grids reach past its end. OpenVDB itself trusts the sizes it reads: a
// truncated file makes it build strings of garbage length and loop or run out
// of memory instead of throwing.
void check_vdb_complete(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const uint64_t size = std::filesystem::file_size(path);
  const auto truncated = [&](const std::string& what) {
    return InputError(path.string(), "", "", fmt::format("truncated or corrupt .vdb file ({}; the file has {} bytes)", what, size));
  };
  const auto read = [&](void* dst, size_t n, const char* what) {
    if (!in.read(static_cast<char*>(dst), std::streamsize(n))) throw truncated(fmt::format("ends inside {}", what));
  };
  const auto skip = [&](uint64_t n, const char* what) {
    const uint64_t at = uint64_t(in.tellg());
    if (n > size - at) throw truncated(fmt::format("{} of {} bytes at offset {} runs past the end", what, n, at));
    in.seekg(std::streamoff(at + n));
  };
  const auto skip_string = [&](const char* what) {
    uint32_t n = 0;
    read(&n, 4, what);
    skip(n, what);
  };
  int64_t magic = 0;
  uint32_t version = 0, library[2];
  read(&magic, 8, "the header");
  if (magic != int64_t(openvdb::OPENVDB_MAGIC)) return;  // not a .vdb: OpenVDB's own open() says so
  read(&version, 4, "the header");
  if (version < openvdb::OPENVDB_FILE_VERSION_BOOST_UUID) return;  // old layouts: left to OpenVDB
  read(library, 8, "the header");
  char has_offsets = 0;
  read(&has_offsets, 1, "the header");
  skip(36, "the file UUID");
  if (!has_offsets) return;
  int32_t count = 0;
  read(&count, 4, "the file metadata");
  for (int32_t i = 0; i < count; ++i) {
    skip_string("a metadata name");
    skip_string("a metadata type");
    skip_string("a metadata value");
  }
  read(&count, 4, "the grid count");
  if (count < 0) throw truncated(fmt::format("grid count {}", count));
  for (int32_t g = 0; g < count; ++g) {
    skip_string("a grid name");
    skip_string("a grid type");
    if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) skip_string("a grid's instance parent");
    int64_t pos[3];  // grid, block, end
    read(pos, sizeof(pos), "a grid descriptor");
    const int64_t at = int64_t(in.tellg());
    // The grid's header (compression, metadata, transform, topology) starts after its
    // descriptor, its data blocks after that, and it ends within the file.
    if (pos[2] < 0 || uint64_t(pos[2]) > size) throw truncated(fmt::format("grid {} ends at offset {}", g, pos[2]));
    if (!(at <= pos[0] && pos[0] <= pos[1] && pos[1] <= pos[2]))
      throw truncated(fmt::format("grid {}'s offsets are out of order: header at {}, data at {}, end at {}, after its "
                                  "descriptor at {}", g, pos[0], pos[1], pos[2], at));
    // Its metadata must lie inside its header: OpenVDB reads the count and the
    // sizes as they come, so a corrupt count made it loop on for billions of entries.
    in.seekg(pos[0]);
    if (version >= openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) skip(4, "a grid's compression flags");
    const uint64_t header_size = uint64_t(pos[1]);
    const auto skip_in_header = [&](uint64_t n, const char* what) {
      const uint64_t here = uint64_t(in.tellg());
      if (n > header_size - std::min(header_size, here))
        throw truncated(fmt::format("grid {}: {} of {} bytes at offset {} runs past the grid's header", g, what, n, here));
      in.seekg(std::streamoff(here + n));
    };
    uint32_t entries = 0, n = 0;
    read(&entries, 4, "a grid's metadata");
    for (uint32_t i = 0; i < entries; ++i)
      for (const char* what : {"a grid metadata name", "a grid metadata type", "a grid metadata value"}) {
        read(&n, 4, what);
        skip_in_header(n, what);
      }
    in.seekg(pos[2]);
  }
}

std::unique_ptr<openvdb::io::File> open_vdb(const std::filesystem::path& path) {
  initialize_openvdb();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path.string(), "", "", "no such file");
  check_vdb_complete(path);
  auto file = std::make_unique<openvdb::io::File>(path.string());
  try {
    // No delayed loading: every voxel is copied out at once anyway, and so every
    // buffer is read, and a corrupt one fails, inside read_grid's error handling.
    file->open(/*delayLoad=*/false);
  } catch (const openvdb::Exception& e) {
    throw InputError(path.string(), "", "", fmt::format("not a readable .vdb file ({})", e.what()));
  }
  return file;
}

// A corrupt grid that passes check_vdb_complete (a value, size or map name changed
// inside it) makes OpenVDB throw: its own exceptions, or bad_alloc / length_error
// for a garbage size. Nothing else happens in readGrid, so any exception is the file's.
openvdb::GridBase::Ptr read_grid(openvdb::io::File& file, const std::string& file_name, const std::string& name) {
  try {
    return file.readGrid(name);
  } catch (const std::exception& e) {
    throw InputError(file_name, "grid", name, fmt::format("cannot be read: corrupt or truncated .vdb file ({})", e.what()));
  }
}

// OpenVDB maps index to world with row vectors (world = index * M, translation
// in the last row); core Transform uses column vectors.
Transform::Mat to_mat(const openvdb::Mat4d& m) {
  Transform::Mat r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r[i][j] = float(m(j, i));
  return r;
}

openvdb::Mat4d to_vdb(const Transform::Mat& m) {
  openvdb::Mat4d r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r(j, i) = m[i][j];
  return r;
}

template <typename T>
T meta_or(const openvdb::GridBase& grid, const std::string& key, T fallback) {
  if (const auto m = grid.getMetadata<openvdb::TypedMetadata<T>>(key)) return m->value();
  return fallback;
}

// World box around voxels [lo, hi] grown by r voxels (the map may be singular here: no inverse needed).
Bounds3 world_box(const Transform::Mat& m, Coord lo, Coord hi, float r) {
  Bounds3 b;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p{c & 1 ? hi[0] + r : lo[0] - r, c & 2 ? hi[1] + r : lo[1] - r, c & 4 ? hi[2] + r : lo[2] - r};
    Vec3 q;
    for (int i = 0; i < 3; ++i) q[i] = m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
    b.extend(q);
  }
  return b;
}

// Every voxel a lookup can see differ from the background: active voxels and
// tiles, and the inactive voxels that leaf nodes store.
std::optional<std::pair<Coord, Coord>> stored_voxels(const openvdb::GridBase& grid) {
  openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
  openvdb::CoordBBox leaves;
  if (grid.baseTree().evalLeafBoundingBox(leaves)) box.expand(leaves);
  if (box.empty()) return std::nullopt;
  return std::pair(Coord{box.min().x(), box.min().y(), box.min().z()}, Coord{box.max().x(), box.max().y(), box.max().z()});
}

// A float copy of a double grid (values rounded to float; transform and metadata kept).
openvdb::FloatGrid::Ptr to_float_grid(const openvdb::DoubleGrid& grid) {
  auto tree = std::make_shared<openvdb::FloatTree>(grid.tree());  // OpenVDB's converting copy: static_cast per value
  openvdb::FloatGrid::Ptr out = openvdb::FloatGrid::create(tree);
  static_cast<openvdb::MetaMap&>(*out) = static_cast<const openvdb::MetaMap&>(grid);
  out->setTransform(grid.transform().copy());
  return out;
}

template <typename GridT>
void scan_values(const GridT& grid, GridInfo* info) {
  using V = typename GridT::ValueType;
  V mn{}, mx{};
  bool any = false;
  for (auto it = grid.cbeginValueAll(); it; ++it) {
    const double v = double(*it);
    const int64_t n = int64_t(it.getVoxelCount());
    if (std::isnan(v)) info->invalid.nan += n;
    else if (std::isinf(v)) info->invalid.inf += n;
    else if (v < 0) info->invalid.negative += n;
    if (!it.isValueOn()) continue;
    if (!any || *it < mn) mn = *it;
    if (!any || *it > mx) mx = *it;
    any = true;
  }
  if (any) info->value_range = std::pair<double, double>(double(mn), double(mx));
}

}  // namespace

VoxelGrid load_concentration_grid(const std::filesystem::path& path, std::string_view grid_name,
                                  GridLoadOptions options) {
  const std::string file_name = path.string();
  auto file = open_vdb(path);
  const std::string name(grid_name);
  if (!file->hasGrid(name)) {
    std::vector<std::string> names;
    for (auto it = file->beginName(); it != file->endName(); ++it) names.push_back(*it);
    std::string problem = names.empty() ? std::string("no such grid; the file holds no grids")
                                        : fmt::format("no such grid; the file has: {}", fmt::join(names, ", "));
    if (const std::string near = nearest_word(name, names); !near.empty())
      problem += fmt::format(" (did you mean \"{}\"?)", near);
    throw InputError(file_name, "grid", name, problem);
  }
  const openvdb::GridBase::Ptr base = read_grid(*file, file_name, name);
  openvdb::FloatGrid::ConstPtr grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base);
  std::string converted_from;
  if (!grid) {
    if (const auto d = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(base)) {
      grid = to_float_grid(*d);
      converted_from = "double";
    } else {
      throw InputError(file_name, "grid", name,
                       fmt::format("is a {} grid; a concentration grid must hold float or double values",
                                   base->valueType()));
    }
  }
  if (!grid->transform().isLinear())
    throw InputError(file_name, "grid", name,
                     "has a non-linear (frustum) transform; only affine index-to-world maps are supported");
  Transform world_from_index;
  try {
    world_from_index = Transform::from_matrix(to_mat(grid->transform().baseMap()->getAffineMap()->getMat4()));
  } catch (const std::domain_error&) {
    throw InputError(file_name, "grid", name, "has a singular index-to-world transform");
  }

  const auto stored = stored_voxels(*grid);
  const Coord lo = stored ? stored->first : Coord{0, 0, 0};
  const Coord hi = stored ? stored->second : Coord{-1, -1, -1};

  GridMetadata meta;
  meta.name = name;
  meta.file = file_name;
  meta.unit = meta_or<std::string>(*grid, "unit", "");
  meta.length_unit = meta_or<std::string>(*grid, "length_unit", "");
  meta.scale = meta_or<float>(*grid, "scale", float(meta_or<double>(*grid, "scale", 1.0)));
  meta.provenance = meta_or<std::string>(*grid, "provenance", "");
  meta.converted_from = converted_from;

  const openvdb::FloatTree& tree = grid->tree();
  // Unregistered accessors: the tree outlives them and is not modified meanwhile.
  using UnsafeAccessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree, false>;
  const float background = tree.background();
  // A brick [o, o+8]^3 touches the eight leaf-sized regions at o + {0, 8}^3;
  // where there is no leaf the whole region holds one (tile or background) value.
  auto may_hold_data = [&](Coord o) {
    UnsafeAccessor acc(tree);
    for (int c = 0; c < 8; ++c) {
      const openvdb::Coord q(o[0] + (c & 1 ? 8 : 0), o[1] + (c & 2 ? 8 : 0), o[2] + (c & 4 ? 8 : 0));
      if (acc.probeConstLeaf(q) || acc.getValue(q) != background) return true;
    }
    return false;
  };
  auto fill = [&](Coord o, float* v) {
    UnsafeAccessor acc(tree);
    for (int z = 0; z < VoxelGrid::kBrickStride; ++z)
      for (int y = 0; y < VoxelGrid::kBrickStride; ++y)
        for (int x = 0; x < VoxelGrid::kBrickStride; ++x)
          v[x + VoxelGrid::kBrickStride * (y + VoxelGrid::kBrickStride * z)] =
              acc.getValue(openvdb::Coord(o[0] + x, o[1] + y, o[2] + z));
  };
  return VoxelGrid::from_bricks(lo, hi, background, world_from_index, std::move(meta), may_hold_data, fill,
                                options.clamp_invalid);
}

void write_concentration_grids(const std::filesystem::path& path, std::span<const DenseGrid> grids) {
  initialize_openvdb();
  openvdb::GridPtrVec out;
  for (const DenseGrid& d : grids) {
    auto grid = openvdb::FloatGrid::create(d.background);
    grid->setName(d.metadata.name);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    try {
      grid->setTransform(openvdb::math::Transform::createLinearTransform(to_vdb(d.world_from_index.matrix())));
    } catch (const openvdb::Exception& e) {
      // OpenVDB refuses nearly singular maps, i.e. voxels of about 1e-5 world units or less.
      const Vec3 voxel{length(d.world_from_index.vector({1, 0, 0})), length(d.world_from_index.vector({0, 1, 0})),
                       length(d.world_from_index.vector({0, 0, 1}))};
      throw InputError(path.string(), d.metadata.name, fmt::format("voxel size {} x {} x {}", voxel.x, voxel.y, voxel.z),
                       fmt::format("OpenVDB cannot store this transform ({}); express the grid in a smaller length "
                                   "unit (e.g. micrometres) and set the scene's length_unit",
                                   e.what()));
    }
    auto acc = grid->getAccessor();
    for (int z = 0; z < d.dims[2]; ++z)
      for (int y = 0; y < d.dims[1]; ++y)
        for (int x = 0; x < d.dims[0]; ++x)
          if (const float v = d.at(x, y, z); !(v == d.background))  // NaN is kept: the loader must see it
            acc.setValue(openvdb::Coord(d.origin[0] + x, d.origin[1] + y, d.origin[2] + z), v);
    grid->tree().prune();
    if (!d.metadata.unit.empty()) grid->insertMeta("unit", openvdb::StringMetadata(d.metadata.unit));
    grid->insertMeta("scale", openvdb::FloatMetadata(d.metadata.scale));
    if (!d.metadata.length_unit.empty())
      grid->insertMeta("length_unit", openvdb::StringMetadata(d.metadata.length_unit));
    if (!d.metadata.provenance.empty())
      grid->insertMeta("provenance", openvdb::StringMetadata(d.metadata.provenance));
    out.push_back(grid);
  }
  try {
    openvdb::io::File file(path.string());
    file.write(out);
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError(path.string(), "", "", fmt::format("cannot write .vdb file ({})", e.what()));
  }
}

GridReport inspect_vdb(const std::filesystem::path& path) {
  auto file = open_vdb(path);
  GridReport report;
  report.file = path.string();
  for (auto it = file->beginName(); it != file->endName(); ++it) {
    const openvdb::GridBase::Ptr grid = read_grid(*file, report.file, *it);
    GridInfo info;
    info.name = *it;
    info.type = grid->valueType();
    info.grid_class = openvdb::GridBase::gridClassToString(grid->getGridClass());
    info.linear_transform = grid->transform().isLinear();
    info.world_from_index = to_mat(grid->transform().baseMap()->getAffineMap()->getMat4());
    const openvdb::Vec3d vs = grid->voxelSize();
    info.voxel_size = Vec3(float(vs.x()), float(vs.y()), float(vs.z()));
    if (const openvdb::CoordBBox b = grid->evalActiveVoxelBoundingBox(); !b.empty()) {
      const Coord lo{b.min().x(), b.min().y(), b.min().z()}, hi{b.max().x(), b.max().y(), b.max().z()};
      info.active_index_bounds = std::pair(lo, hi);
      info.active_world_bounds = world_box(info.world_from_index, lo, hi, 0.5f);
    }
    if (const auto stored = stored_voxels(*grid)) {
      info.stored_index_bounds = stored;
      for (const Interpolation i : {Interpolation::nearest, Interpolation::trilinear})
        info.medium_world_bounds[int(i)] =
            world_box(info.world_from_index, stored->first, stored->second, support_radius(i));
    }
    info.active_voxels = int64_t(grid->activeVoxelCount());
    info.memory_bytes = int64_t(grid->memUsage());
    if (const auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid)) scan_values(*f, &info);
    else if (const auto d = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(grid)) scan_values(*d, &info);
    for (auto m = grid->beginMeta(); m != grid->endMeta(); ++m) info.metadata.emplace_back(m->first, m->second->str());
    report.grids.push_back(std::move(info));
  }
  return report;
}

}  // namespace chlorovdb
