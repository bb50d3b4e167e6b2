// `chlorovdb merge PART... -o OUT.exr`: partial renders (--crop, --sample-range,
// MPI rank checkpoints) combined into the image one run would give
// (checkpoint/merge.h, docs/distributed.md), with a PNG preview beside it.
#include <fmt/format.h>

#include "checkpoint/merge.h"
#include "cli/commands.h"
#include "io/image.h"

namespace chlorovdb::cli {

namespace {

struct MergeArgs {
  std::vector<std::filesystem::path> parts;
  std::filesystem::path output;
  std::optional<float> exposure;
};

int merge(const MergeArgs& a) {
  MergeSummary summary;
  const Image image = merge_parts(a.parts, &summary);
  std::filesystem::path out = a.output;
  if (out.extension() != ".exr") out += ".exr";
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::filesystem::path png = out;
  png.replace_extension(".png");
  write_exr(out, image);
  write_png(png, image.layers[0], image.width, image.height, a.exposure.value_or(0.f));
  fmt::print(stderr, "merged {} {} ({}): {}x{}, {} spp (samples {}), wrote {} and {}\n", summary.parts,
             summary.exact ? "checkpoints" : "EXR parts", summary.exact ? "exact double sums" : "float means",
             image.width, image.height, summary.samples_per_pixel, to_string(summary.ranges), out.string(), png.string());
  return 0;
}

}  // namespace

Command add_merge_command(CLI::App& app) {
  auto args = std::make_shared<MergeArgs>();
  CLI::App* sub = app.add_subcommand(
      "merge",
      "Combine partial renders (--crop / --sample-range parts of one scene and seed) into the image one run would give");
  sub->add_option("parts", args->parts,
                  "Parts: all EXRs from `render` (weighted by their sample counts, float rounding) or all --checkpoint "
                  "files (exact sums)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", args->output, "Output EXR (a PNG preview is written beside it)")->required();
  sub->add_option("--exposure", args->exposure, "PNG preview exposure in stops")->check(Real(-40, 40));
  return {sub, [args] { return merge(*args); }};
}

}  // namespace chlorovdb::cli
