// cloud_to_vdb: the shared pbrt-v4 benchmark's density field (a raw float32
// N^3 array, x fastest, cell-centred over [-1, 1]^3) -> a .vdb grid "density"
// that chlorovdb samples exactly as pbrt-v4's uniformgrid medium does.
//
//   cloud_to_vdb RAW.raw OUT.vdb [--mirror-x] [--name density]
//   cloud_to_vdb --generate OUT.vdb [--mirror-x] [--raw-out FIELD.raw]
//
// Voxel (i,j,k) has its centre at -1 + (i+1/2) h, h = 2/N: world_from_index =
// translate(-1 + h/2) * scale(h). VoxelGrid samples voxel values at integer
// index points (= voxel centres) and interpolates trilinearly towards the
// background 0 beyond the outermost centres, as pbrt-v4's SampledGrid does
// (its out-of-range lookups return 0), so the two fields agree everywhere in
// the cube, and the medium's box (the voxel cells) is exactly [-1, 1]^3.
//
// --mirror-x stores raw[N-1-i] in voxel i: the field mirrored in x (x -> -x),
// with the same positive-determinant transform. pbrt-v4's camera is
// left-handed (image right = up x view), chlorovdb's right-handed (image right
// = view x up), so the benchmark scene mirrors the whole scene in x (field,
// light direction, camera) to produce pbrt's image pixel for pixel.
//
// --generate recomputes the field of ../shared/bench/cloud/gen_cloud.py in
// double precision (for machines without numpy); it agrees with numpy's file
// to float rounding (bench.sh reports the largest difference when both exist).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "grids/vdb_file.h"

namespace {

using chlorovdb::DenseGrid;
using chlorovdb::Transform;
using chlorovdb::Vec3;

[[noreturn]] void usage(const char* msg) {
  std::fprintf(stderr,
               "%s\nusage: cloud_to_vdb RAW.raw OUT.vdb [--mirror-x] [--name NAME]\n"
               "       cloud_to_vdb --generate OUT.vdb [--mirror-x] [--name NAME] [--raw-out FIELD.raw]\n",
               msg);
  std::exit(2);
}

// gen_cloud.py, line by line (numpy computes in float64, then casts to float32).
std::vector<float> generate_field(int N) {
  struct Blob {
    double cx, cy, cz, s, a;
  };
  const Blob blobs[] = {{0.00, 0.00, 0.00, 0.30, 1.00},
                        {0.30, 0.15, 0.10, 0.20, 0.70},
                        {-0.28, 0.10, -0.15, 0.22, 0.80},
                        {0.10, -0.25, 0.25, 0.18, 0.60},
                        {-0.10, 0.30, -0.05, 0.16, 0.50}};
  const double h = 2.0 / N;
  auto w = [](double t) { return (1 - t * t) * (1 - t * t); };
  std::vector<double> d(size_t(N) * N * N);
  double dmax = 0;
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const double x = -1.0 + (i + 0.5) * h, y = -1.0 + (j + 0.5) * h, z = -1.0 + (k + 0.5) * h;
        double v = 0;
        for (const Blob& b : blobs)
          v += b.a * std::exp(-((x - b.cx) * (x - b.cx) + (y - b.cy) * (y - b.cy) + (z - b.cz) * (z - b.cz)) /
                              (2 * b.s * b.s));
        v *= w(x) * w(y) * w(z);
        d[(size_t(k) * N + j) * N + i] = v;
        dmax = std::max(dmax, v);
      }
  std::vector<float> f(d.size());
  for (size_t n = 0; n < d.size(); ++n) f[n] = float(d[n] / dmax);
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> pos;
  bool mirror = false, generate = false;
  std::string name = "density", raw_out;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--mirror-x") mirror = true;
    else if (s == "--generate") generate = true;
    else if (s == "--name" && a + 1 < argc) name = argv[++a];
    else if (s == "--raw-out" && a + 1 < argc) raw_out = argv[++a];
    else if (s.rfind("--", 0) == 0) usage(("unknown option " + s).c_str());
    else pos.push_back(s);
  }
  if (pos.size() != (generate ? 1u : 2u)) usage("wrong number of arguments");
  const std::string out = pos.back();

  std::vector<float> raw;
  int N = 64;
  if (generate) {
    raw = generate_field(N);
    if (!raw_out.empty()) {
      std::ofstream f(raw_out, std::ios::binary);
      f.write(reinterpret_cast<const char*>(raw.data()), std::streamsize(raw.size() * sizeof(float)));
      if (!f) usage(("cannot write " + raw_out).c_str());
    }
  } else {
    std::ifstream f(pos[0], std::ios::binary | std::ios::ate);
    if (!f) usage(("cannot open " + pos[0]).c_str());
    const size_t bytes = size_t(f.tellg());
    N = int(std::lround(std::cbrt(double(bytes / sizeof(float)))));
    if (bytes % sizeof(float) != 0 || size_t(N) * N * N * sizeof(float) != bytes)
      usage(("not an N^3 float32 array: " + pos[0]).c_str());
    raw.resize(size_t(N) * N * N);
    f.seekg(0);
    f.read(reinterpret_cast<char*>(raw.data()), std::streamsize(bytes));
    if (!f) usage(("cannot read " + pos[0]).c_str());
  }

  DenseGrid g({N, N, N});
  float vmax = 0.f;
  size_t zeros = 0;
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const float v = raw[(size_t(k) * N + j) * N + (mirror ? N - 1 - i : i)];
        if (!(v >= 0.f) || !std::isfinite(v)) usage("the field holds a negative or non-finite value");
        g.at(i, j, k) = v;
        vmax = std::max(vmax, v);
        zeros += v == 0.f;
      }
  const float h = 2.f / float(N);  // exact for N a power of two
  g.world_from_index = Transform::translate(Vec3(-1.f + 0.5f * h)) * Transform::scale(Vec3(h));
  g.background = 0.f;
  g.metadata.name = name;
  g.metadata.unit = "";  // dimensionless density: the scene gives units and scales
  g.metadata.scale = 1.f;
  g.metadata.provenance = std::string("pbrt-v4 cloud benchmark field (shared/bench/cloud/gen_cloud.py), ") +
                          (generate ? "regenerated by cloud_to_vdb --generate" : "from " + pos[0]) +
                          (mirror ? ", mirrored in x (x -> -x) for chlorovdb's right-handed camera" : "") +
                          "; voxel centre (i,j,k) = -1 + (i+1/2) h, h = 2/N";
  chlorovdb::write_concentration_grid(out, g);
  std::printf("wrote %s: %d^3 voxels, h = %g, max %g, %zu zero voxels%s\n", out.c_str(), N, double(h), double(vmax),
              zeros, mirror ? ", mirrored in x" : "");
  return 0;
}
