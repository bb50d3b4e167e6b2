// regression_render: the render regression harness (tests/regression/regression.h).
//
//   regression_render --write REF SCENE   render the reference estimate into REF
//   regression_render --check REF SCENE   render the CI estimate and test it against REF
//
// Both render SCENE at kWidth pixels across (its aspect kept) in independent
// batches of samples through the library (load_scene, render), with fixed seeds;
// they differ only in batch count, samples per batch and seed. --check exits 1
// when any pixel or 8x8 block differs beyond what the noise of both explains.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "core/error.h"
#include "integrator/render.h"
#include "regression.h"
#include "scene/param_reader.h"
#include "scene/scene_loader.h"

using namespace chlorovdb;
using namespace chlorovdb::regression;

namespace {

constexpr int kWidth = 32;
constexpr char kMagic[8] = {'C', 'V', 'D', 'B', 'R', 'E', 'F', '1'};
struct Plan {
  int batches, spp_per_batch;
  uint64_t seed;
};
constexpr Plan kReference{64, 16, 1000};
constexpr Plan kCheck{64, 2, 7};
constexpr double kAlpha = 1e-3;  // family-wise false-failure rate per scene

Estimate render_batches(const std::filesystem::path& scene_file, const Plan& plan) {
  const nlohmann::json json = ParamReader::parse_file(scene_file);
  int w = 512, h = 512;
  if (json.contains("render") && json["render"].contains("resolution"))
    w = json["render"]["resolution"][0].get<int>(), h = json["render"]["resolution"][1].get<int>();
  SceneOverrides o;
  o.width = kWidth;
  o.height = std::max(1, int(std::lround(double(kWidth) * h / w)));
  o.seed = plan.seed;
  const Scene scene = load_scene(scene_file, o);
  BatchAccumulator acc(*o.width, *o.height);
  for (int b = 0; b < plan.batches; ++b) {
    Film film(*o.width, *o.height, film_layer_names(), scene.settings.color_space);
    RenderOptions r;
    r.first_sample = b * plan.spp_per_batch;  // disjoint sample ranges: independent random streams
    r.spp = plan.spp_per_batch;
    r.seed = plan.seed;
    r.threads = 0;
    render(scene, film, r);
    std::vector<double> xyz(film.raw_xyz(kLayerTotal));
    for (double& v : xyz) v /= plan.spp_per_batch;
    acc.add_batch(xyz);
  }
  Estimate e = acc.estimate();
  e.spp_per_batch = plan.spp_per_batch;
  e.seed = plan.seed;
  return e;
}

void write_estimate(const std::filesystem::path& path, const Estimate& e) {
  std::ofstream out(path, std::ios::binary);
  out.write(kMagic, 8);
  const int32_t head[4] = {e.width, e.height, e.batches, e.spp_per_batch};
  out.write(reinterpret_cast<const char*>(head), sizeof head);
  out.write(reinterpret_cast<const char*>(&e.seed), sizeof e.seed);
  const uint64_t n = e.mean.size();
  out.write(reinterpret_cast<const char*>(&n), sizeof n);
  for (const auto* v : {&e.mean, &e.var})
    for (double x : *v) {
      const float f = float(x);
      out.write(reinterpret_cast<const char*>(&f), sizeof f);
    }
  if (!out) throw InputError(path.string(), "", "", "cannot write the reference");
}

Estimate read_estimate(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8];
  Estimate e;
  int32_t head[4];
  uint64_t n = 0;
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0 || !in.read(reinterpret_cast<char*>(head), sizeof head) ||
      !in.read(reinterpret_cast<char*>(&e.seed), sizeof e.seed) || !in.read(reinterpret_cast<char*>(&n), sizeof n) ||
      n > (1u << 24))
    throw InputError(path.string(), "", "", "not a regression reference (regenerate: tools/make_regression_refs.sh)");
  e.width = head[0], e.height = head[1], e.batches = head[2], e.spp_per_batch = head[3];
  for (auto* v : {&e.mean, &e.var}) {
    std::vector<float> f(n);
    if (!in.read(reinterpret_cast<char*>(f.data()), std::streamsize(n * sizeof(float))))
      throw InputError(path.string(), "", "", "truncated regression reference");
    v->assign(f.begin(), f.end());
  }
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 || (std::strcmp(argv[1], "--write") != 0 && std::strcmp(argv[1], "--check") != 0)) {
    std::fprintf(stderr, "usage: regression_render --write|--check REF SCENE\n");
    return 2;
  }
  try {
    const bool write = std::strcmp(argv[1], "--write") == 0;
    const auto start = std::chrono::steady_clock::now();
    const Estimate e = render_batches(argv[3], write ? kReference : kCheck);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (write) {
      write_estimate(argv[2], e);
      fmt::print("{}: wrote {} ({}x{}, {} batches of {} spp, {:.1f} s)\n", argv[3], argv[2], e.width, e.height,
                 e.batches, e.spp_per_batch, seconds);
      return 0;
    }
    const Estimate ref = read_estimate(argv[2]);
    if (ref.width != e.width || ref.height != e.height || ref.mean.size() != e.mean.size()) {
      fmt::print(stderr, "{}: reference is {}x{}, the render {}x{}: regenerate (tools/make_regression_refs.sh)\n",
                 argv[2], ref.width, ref.height, e.width, e.height);
      return 1;
    }
    const Comparison c = compare(e, ref, kAlpha);
    const size_t pixels = size_t(e.width) * e.height * 3;
    const size_t s = c.worst;
    const std::string where =
        s < pixels ? fmt::format("pixel ({}, {}) channel {}", s / 3 % e.width, s / 3 / e.width, "XYZ"[s % 3])
                   : fmt::format("8x8 block {} channel {}", (s - pixels) / 3, "XYZ"[s % 3]);
    fmt::print("{}: {} statistics, {} rejected (Holm, alpha {}); worst {}: {:.4g} vs reference {:.4g}, t = {:.2f}, "
               "p = {:.3g}; {:.1f} s\n",
               argv[3], c.tests, c.rejected, kAlpha, where, e.mean[s], ref.mean[s], c.worst_t, c.min_p, seconds);
    return c.failed() ? 1 : 0;
  } catch (const std::exception& ex) {
    fmt::print(stderr, "regression_render: {}\n", ex.what());
    return 2;
  }
}
