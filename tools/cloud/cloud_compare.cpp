// cloud_compare: our render(s) of the cloud benchmark against pbrt-v4's reference.
//
//   cloud_compare REF.exr OURS.exr [OURS2.exr ...] [--layer total] [--ref-noise-mse X] [--mirror-x]
//
// OURS files are independent renders of the same scene with equal spp (different
// seeds); they are averaged. Over all W x H x 3 values (linear RGB) it prints,
// one "key value" per line:
//   rmse                 RMSE of the average against REF
//   mse                  its square
//   mean_ours, mean_ref  mean pixel value (all channels)
//   rel_diff_means       mean_ours / mean_ref - 1 (the bias measure: noise averages out)
//   rel_diff_means_sigma its standard error from our noise (>= 2 files; REF's is ~16x smaller)
//   rel_diff_r/g/b       the same per channel
//   mean_abs_rel_diff    mean over values of |ours - ref| / ref (noise dominated)
//   noise_mse_ours       the average's own noise: per-value sample variance over the
//                        OURS files / their count (needs >= 2 files), averaged over values
//   noise_mse_ref        REF's noise (--ref-noise-mse; default from pbrt-v4's own figures:
//                        per-sample variance 0.0451 / 8192 spp = 5.5e-6)
//   expected_rmse        sqrt(noise_mse_ours + noise_mse_ref): what pure noise gives
//   excess_mse           mse - noise_mse_ours - noise_mse_ref (bias^2 + estimation error)
//   excess_mse_sigma     standard error of excess_mse (from the per-value spread)
//   rmse_mirrored        RMSE with ours mirrored left-right (an orientation check)
//   corner_ref/ours      pixel (0,0), RGB (background: pbrt reads 0.3016 0.2370 0.2278)
//   time_s               sum of the OURS files' chlorovdb:wall_time_s (if present)
//   spp                  sum of their chlorovdb:spp
// --mirror-x mirrors OURS left-right before comparing (for a scene that is not mirrored).
// --furnace R,G,B: no REF; OURS should be that colour everywhere (a white-furnace scene):
//   prints furnace_all and furnace_centre, the mean of OURS over the whole image and over its
//   central quarter (the densest part) divided by R,G,B, averaged over the channels, and
//   furnace_centre_sigma, the standard error of the latter (from the pixel spread).
// --dump PREFIX writes PREFIX_ref.f32 and PREFIX_ours.f32 (H x W x 3 float32, top row first)
// for analysis with numpy.
#include <cmath>
#include <fstream>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <variant>
#include <vector>

#include "io/image.h"

namespace {

using chlorovdb::Image;
using chlorovdb::ImageLayer;

[[noreturn]] void usage(const std::string& msg) {
  std::fprintf(stderr,
               "%s\nusage: cloud_compare REF.exr OURS.exr [OURS2.exr ...] [--layer total] [--ref-noise-mse X] "
               "[--mirror-x] [--dump PREFIX]\n       cloud_compare --furnace R,G,B OURS.exr\n",
               msg.c_str());
  std::exit(2);
}

// The RGB values of `layer` (or the first layer), W*H*3 interleaved.
std::vector<float> rgb_of(const Image& img, const std::string& layer, const std::string& file) {
  const ImageLayer* l = img.find_layer(layer);
  if (!l) l = &img.layers.at(0);
  const size_t nc = l->channels.size();
  if (nc < 3) usage(file + ": layer has fewer than 3 channels");
  std::vector<float> v(size_t(img.width) * img.height * 3);
  for (size_t p = 0; p < size_t(img.width) * img.height; ++p)
    for (int c = 0; c < 3; ++c) v[p * 3 + c] = l->pixels[p * nc + c];
  return v;
}

double meta_number(const Image& img, const char* key) {
  const auto* v = img.metadata.find(key);
  if (!v) return NAN;
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<int>(v)) return *i;
  return std::atof(std::get<std::string>(*v).c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  std::string layer = "total";
  double ref_noise_mse = 0.0451 / 8192;  // pbrt-v4's RMSE table: MSE(spp) = v/spp + v/8192, v = 0.0451
  bool mirror = false;
  std::string dump;
  double furnace[3] = {0, 0, 0};
  bool furnace_mode = false;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--layer" && a + 1 < argc) layer = argv[++a];
    else if (s == "--ref-noise-mse" && a + 1 < argc) ref_noise_mse = std::atof(argv[++a]);
    else if (s == "--mirror-x") mirror = true;
    else if (s == "--dump" && a + 1 < argc) dump = argv[++a];
    else if (s == "--furnace" && a + 1 < argc) {
      furnace_mode = std::sscanf(argv[++a], "%lf,%lf,%lf", &furnace[0], &furnace[1], &furnace[2]) == 3;
      if (!furnace_mode) usage("--furnace expects R,G,B");
    }
    else if (s.rfind("--", 0) == 0) usage("unknown option " + s);
    else files.push_back(s);
  }
  if (furnace_mode) {
    if (files.size() != 1) usage("--furnace takes exactly one image");
    const Image img = chlorovdb::read_exr(files[0]);
    const std::vector<float> v = rgb_of(img, layer, files[0]);
    const int W = img.width, H = img.height;
    double all = 0, centre = 0, centre2 = 0;
    int n_centre = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        double r = 0;
        for (int c = 0; c < 3; ++c) r += v[(size_t(y) * W + x) * 3 + c] / furnace[c] / 3;
        all += r;
        if (x >= W / 4 && x < 3 * W / 4 && y >= H / 4 && y < 3 * H / 4) {
          centre += r;
          centre2 += r * r;
          ++n_centre;
        }
      }
    const double mc = centre / n_centre;
    std::printf("furnace_all %.5f\nfurnace_centre %.5f\nfurnace_centre_sigma %.5f\n", all / (double(W) * H), mc,
                std::sqrt(std::max(0.0, centre2 / n_centre - mc * mc) / n_centre));
    return 0;
  }
  if (files.size() < 2) usage("need REF and at least one OURS");

  const Image ref_img = chlorovdb::read_exr(files[0]);
  const int W = ref_img.width, H = ref_img.height;
  const std::vector<float> ref = rgb_of(ref_img, "", files[0]);
  const size_t n = ref.size();
  const int k = int(files.size()) - 1;
  std::vector<double> sum(n, 0.0), sum2(n, 0.0);
  std::vector<double> pixel_sums(size_t(k) * (n / 3), 0.0);  // per file, per pixel: R + G + B
  double time_s = 0, spp = 0;
  for (int f = 1; f <= k; ++f) {
    const Image img = chlorovdb::read_exr(files[f]);
    if (img.width != W || img.height != H) usage(files[f] + ": size differs from the reference");
    std::vector<float> v = rgb_of(img, layer, files[f]);
    if (mirror)
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W / 2; ++x)
          for (int c = 0; c < 3; ++c)
            std::swap(v[(size_t(y) * W + x) * 3 + c], v[(size_t(y) * W + (W - 1 - x)) * 3 + c]);
    for (size_t i = 0; i < n; ++i) {
      sum[i] += v[i];
      sum2[i] += double(v[i]) * v[i];
      pixel_sums[size_t(f - 1) * (n / 3) + i / 3] += v[i];
    }
    time_s += meta_number(img, "wall_time_s");
    spp += meta_number(img, "spp");
  }
  std::vector<double> ours(n), noise_var(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    ours[i] = sum[i] / k;
    if (k >= 2) noise_var[i] = std::max(0.0, (sum2[i] - k * ours[i] * ours[i]) / (k - 1)) / k;
  }
  // Variance of the average image's mean: pixels are independent, a pixel's channels are not.
  double mean_var = 0;
  if (k >= 2)
    for (size_t p = 0; p < n / 3; ++p) {
      double s = 0, s2 = 0;
      for (int f = 0; f < k; ++f) {
        const double v = pixel_sums[size_t(f) * (n / 3) + p];
        s += v;
        s2 += v * v;
      }
      const double m = s / k;
      mean_var += std::max(0.0, (s2 - k * m * m) / (k - 1)) / k;
    }
  mean_var /= double(n) * double(n);

  if (!dump.empty()) {
    std::vector<float> o(ours.begin(), ours.end());
    std::ofstream(dump + "_ref.f32", std::ios::binary).write(reinterpret_cast<const char*>(ref.data()), std::streamsize(n * 4));
    std::ofstream(dump + "_ours.f32", std::ios::binary).write(reinterpret_cast<const char*>(o.data()), std::streamsize(n * 4));
  }
  double se = 0, se_m = 0, so = 0, sr = 0, sard = 0, noise = 0;
  double ch_o[3] = {}, ch_r[3] = {};
  // Per-value terms of the excess, for its standard error.
  double ex_sum = 0, ex_sum2 = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * W + x) * 3 + c, im = (size_t(y) * W + (W - 1 - x)) * 3 + c;
        const double d = ours[i] - ref[i], dm = ours[im] - ref[i];
        se += d * d;
        se_m += dm * dm;
        so += ours[i];
        sr += ref[i];
        ch_o[c] += ours[i];
        ch_r[c] += ref[i];
        if (ref[i] > 0) sard += std::fabs(d) / ref[i];
        noise += noise_var[i];
        const double e = d * d - noise_var[i];
        ex_sum += e;
        ex_sum2 += e * e;
      }
  const double mse = se / n, noise_ours = noise / n;
  const double excess = mse - noise_ours - ref_noise_mse;
  const double ex_mean = ex_sum / n, ex_var = std::max(0.0, ex_sum2 / n - ex_mean * ex_mean);
  std::printf("files %d\n", k);
  std::printf("spp %g\n", spp);
  std::printf("time_s %.4f\n", time_s);
  std::printf("rmse %.6g\n", std::sqrt(mse));
  std::printf("mse %.6g\n", mse);
  std::printf("mean_ours %.6f\n", so / n);
  std::printf("mean_ref %.6f\n", sr / n);
  std::printf("rel_diff_means %+.5f\n", so / sr - 1);
  if (k >= 2) std::printf("rel_diff_means_sigma %.5f\n", std::sqrt(mean_var) / (sr / n));
  const char* names = "rgb";
  for (int c = 0; c < 3; ++c) std::printf("rel_diff_%c %+.5f\n", names[c], ch_o[c] / ch_r[c] - 1);
  std::printf("mean_abs_rel_diff %.5f\n", sard / n);
  if (k >= 2) std::printf("noise_mse_ours %.6g\n", noise_ours);
  std::printf("noise_mse_ref %.6g\n", ref_noise_mse);
  if (k >= 2) {
    std::printf("expected_rmse %.6g\n", std::sqrt(noise_ours + ref_noise_mse));
    std::printf("excess_mse %.4g\n", excess);
    std::printf("excess_mse_sigma %.4g\n", std::sqrt(ex_var / n));
  }
  std::printf("rmse_mirrored %.6g\n", std::sqrt(se_m / n));
  std::printf("corner_ref %.4f %.4f %.4f\n", ref[0], ref[1], ref[2]);
  std::printf("corner_ours %.4f %.4f %.4f\n", ours[0], ours[1], ours[2]);
  return 0;
}
