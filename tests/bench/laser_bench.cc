// Real data through the fusion engine (issue item 9): the CARMEN laser logs of
// shared/data/laser, lines extracted per scan by split-and-merge
// (client/robot/split_and_merge.h), moved into the map frame by the corrected laser
// pose, fed to FusionEngine one observation per scan, as the paper (no chain
// guard, no wall consolidation) and with the defaults (both on). Reports raw and fused feature
// counts and the share of valid scan points (range < max range) within 5 cm and 10 cm of a fused
// segment, and the published wall length on cells laser beams passed through
// (seen_through.h: issue 40's measure of walls the building does not have); a
// markdown table on stdout, for docs/fusion-real-data.md; writes
// docs/fusion-laser-<log>.svg.
//
//   laser_bench [--data DIR] [--docs DIR] [--no-write] [--guard-rms M] [--guard-ratio R]
//               [--wall-offset M] [--occluded-gap M] [--occluded-ratio R]
//               [--consolidate 0|1] [--free-min-count N] [--bounded] [--max-component-nodes N]
// (they set the default run's FusionParams of those names; otherwise the defaults.
// Both runs use the exact mode, the reference, unless --bounded: mapd's mode,
// with its cost caps.)
// With MAPD_BENCH_WORST set, each run also prints its 8 published segments with
// the most seen-through length on stderr (where to look in the pictures).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "bench/carmen.h"
#include "bench/seen_through.h"
#include "fusion/engine.h"
#include "fusion/grid_index.h"

namespace mapd::bench {
namespace {

using fusion::FusedFeature;
using fusion::FusionEngine;
using fusion::FusionParams;
using fusion::GroundFeature;
using geometry::Segment2;
using geometry::Vec2;

// Share of points within 5 and 10 cm of a segment (point-to-segment distance).
struct Coverage {
  double within_5cm = 0.0;
  double within_10cm = 0.0;
};

Coverage MeasureCoverage(const std::vector<ScanLines>& scans,
                         const std::vector<Segment2>& segments) {
  constexpr double kCellM = 1.0;
  constexpr double kReachM = 0.1;
  fusion::UniformGrid<uint32_t> grid(kCellM);
  std::unordered_map<fusion::CellKey, std::vector<uint32_t>, fusion::CellKeyHash> cells;
  for (uint32_t k = 0; k < segments.size(); ++k) {
    const Segment2& s = segments[k];
    const fusion::CellKey lo = grid.KeyOf(s.a.cwiseMin(s.b) - Vec2(kReachM, kReachM));
    const fusion::CellKey hi = grid.KeyOf(s.a.cwiseMax(s.b) + Vec2(kReachM, kReachM));
    for (int64_t x = lo.x; x <= hi.x; ++x) {
      for (int64_t y = lo.y; y <= hi.y; ++y) {
        // Only cells the segment's 10 cm band can reach.
        const Vec2 centre((static_cast<double>(x) + 0.5) * kCellM,
                          (static_cast<double>(y) + 0.5) * kCellM);
        if (geometry::PointSegmentDistance(centre, s) > kCellM * 0.7072 + kReachM) continue;
        cells[{x, y}].push_back(k);
      }
    }
  }
  size_t total = 0, near5 = 0, near10 = 0;
  for (const ScanLines& scan : scans) {
    for (const Vec2& p : scan.points) {
      ++total;
      auto it = cells.find(grid.KeyOf(p));
      if (it == cells.end()) continue;
      double best = 1e300;
      for (uint32_t k : it->second)
        best = std::min(best, geometry::PointSegmentDistance(p, segments[k]));
      near5 += best <= 0.05;
      near10 += best <= 0.10;
    }
  }
  Coverage c;
  c.within_5cm = total == 0 ? 0.0 : static_cast<double>(near5) / static_cast<double>(total);
  c.within_10cm = total == 0 ? 0.0 : static_cast<double>(near10) / static_cast<double>(total);
  return c;
}

struct RunResult {
  size_t published = 0;
  size_t clusters = 0;
  size_t retired = 0;  // walls retired as seen through (fusion.retire_views)
  std::vector<Segment2> retired_segments;
  SeenThroughGrid::Totals retired_seen;  // of the retired walls, by the bench's own measure
  size_t identical_pairs = 0;            // published features with the same segment
  double engine_s = 0.0;
  Coverage coverage;
  SeenThroughGrid::Totals seen;  // seen-through / published wall length, metres
  std::vector<Segment2> segments;
};

RunResult Fuse(const std::vector<ScanLines>& scans, const SeenThroughGrid& seen,
               const FusionParams& params) {
  FusionEngine engine(params);
  uint64_t next_id = 1;
  const auto start = std::chrono::steady_clock::now();
  for (size_t s = 0; s < scans.size(); ++s) {
    std::vector<GroundFeature> features;
    for (const Segment2& line : scans[s].lines) {
      GroundFeature f;
      f.id = next_id++;
      f.segment = line;
      features.push_back(f);
    }
    // The laser's position is the sensor origin, as mapd passes T_map_sensor's
    // translation: with free-space evidence on, the default run counts what the
    // rays crossed (fusion/free_space.h).
    const Status status = engine.AddFrom(s + 1, 0, scans[s].sensor_xy_m, features);
    if (!status.ok()) {
      std::fprintf(stderr, "scan %zu: %s\n", s, status.ToString().c_str());
      std::exit(1);
    }
  }
  RunResult r;
  r.engine_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const FusedFeature& f : engine.Published()) r.segments.push_back(f.segment);
  r.published = r.segments.size();
  r.clusters = engine.cluster_count();
  r.retired = engine.retired_count();
  for (const FusedFeature& f : engine.Retired()) r.retired_segments.push_back(f.fitted);
  r.retired_seen = seen.Measure(r.retired_segments);
  for (size_t i = 0; i < r.segments.size(); ++i) {
    for (size_t j = i + 1; j < r.segments.size(); ++j) {
      const Segment2& p = r.segments[i];
      const Segment2& q = r.segments[j];
      r.identical_pairs += (p.a == q.a && p.b == q.b) || (p.a == q.b && p.b == q.a);
    }
  }
  r.coverage = MeasureCoverage(scans, r.segments);
  r.seen = seen.Measure(r.segments);
  if (std::getenv("MAPD_BENCH_WORST") != nullptr) {  // debugging: the worst walls
    std::vector<std::pair<double, size_t>> worst;
    for (size_t i = 0; i < r.segments.size(); ++i)
      worst.push_back({seen.SeenThroughLength(r.segments[i]), i});
    std::sort(worst.rbegin(), worst.rend());
    for (size_t k = 0; k < std::min<size_t>(8, worst.size()); ++k) {
      const Segment2& s = r.segments[worst[k].second];
      std::fprintf(stderr, "  %.2f m seen through: (%.2f %.2f)-(%.2f %.2f) len %.2f\n",
                   worst[k].first, s.a.x(), s.a.y(), s.b.x(), s.b.y(), s.length());
    }
  }
  return r;
}

// The window holding 99% of the points in x and in y.
void Window(const std::vector<ScanLines>& scans, Vec2* lo, Vec2* hi) {
  std::vector<double> xs, ys;
  for (const ScanLines& s : scans) {
    for (size_t i = 0; i < s.points.size(); i += 7) {
      xs.push_back(s.points[i].x());
      ys.push_back(s.points[i].y());
    }
  }
  const auto quantile = [](std::vector<double>& v, double q) {
    const size_t k = static_cast<size_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
    return v[k];
  };
  *lo = Vec2(quantile(xs, 0.005), quantile(ys, 0.005)) - Vec2(1, 1);
  *hi = Vec2(quantile(xs, 0.995), quantile(ys, 0.995)) + Vec2(1, 1);
}

// Two panels side by side: the paper, the defaults. Seen-through cells (laser
// beams passed there: an opening) pale green, scan points (10 cm cells) faint,
// fused segments bold, in black where they lie on seen-through cells.
bool WriteSvg(const std::string& path, const std::string& log, const std::vector<ScanLines>& scans,
              const SeenThroughGrid& seen, const RunResult& off, const RunResult& on) {
  Vec2 lo, hi;
  Window(scans, &lo, &hi);
  const double span = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const double scale = 760.0 / span;  // px per metre
  const double w = (hi.x() - lo.x()) * scale, h = (hi.y() - lo.y()) * scale;
  constexpr double kCellM = 0.1;
  std::unordered_set<int64_t> occupied;
  std::string dots;
  for (const ScanLines& s : scans) {
    for (const Vec2& p : s.points) {
      if (p.x() < lo.x() || p.y() < lo.y() || p.x() > hi.x() || p.y() > hi.y()) continue;
      const int64_t cx = static_cast<int64_t>((p.x() - lo.x()) / kCellM);
      const int64_t cy = static_cast<int64_t>((p.y() - lo.y()) / kCellM);
      if (!occupied.insert(cx * 1000003 + cy).second) continue;
      char buf[64];
      std::snprintf(buf, sizeof(buf), "M%.1f %.1fh%.1fv%.1fh-%.1fz", cx * kCellM * scale,
                    h - (cy + 1) * kCellM * scale, kCellM * scale, kCellM * scale, kCellM * scale);
      dots += buf;
    }
  }
  std::string open_cells;  // runs of seen-through cells along each row
  for (double y = lo.y(); y < hi.y(); y += kCellM) {
    for (double x = lo.x(); x < hi.x(); x += kCellM) {
      if (!seen.SeenThrough(Vec2(x + 0.5 * kCellM, y + 0.5 * kCellM))) continue;
      double end = x + kCellM;
      while (end < hi.x() && seen.SeenThrough(Vec2(end + 0.5 * kCellM, y + 0.5 * kCellM))) {
        end += kCellM;
      }
      char buf[80];
      std::snprintf(buf, sizeof(buf), "M%.1f %.1fh%.1fv%.1fh-%.1fz", (x - lo.x()) * scale,
                    h - (y - lo.y() + kCellM) * scale, (end - x) * scale, kCellM * scale,
                    (end - x) * scale);
      open_cells += buf;
      x = end;
    }
  }
  const auto to_px = [&](const Vec2& p) {
    return Vec2((p.x() - lo.x()) * scale, h - (p.y() - lo.y()) * scale);
  };
  std::ofstream out(path);
  if (!out) return false;
  const double panel = w + 20.0;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << static_cast<int>(2 * panel + 20)
      << "\" height=\"" << static_cast<int>(h + 76)
      << "\" font-family=\"sans-serif\" font-size=\"14\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  const RunResult* runs[2] = {&off, &on};
  const char* titles[2] = {"the paper (no guard, no consolidation)",
                           "default (guard, consolidation)"};
  for (int k = 0; k < 2; ++k) {
    const RunResult& r = *runs[k];
    char title[160], figures[200];
    std::snprintf(title, sizeof(title), "%s, %s", log.c_str(), titles[k]);
    std::snprintf(figures, sizeof(figures),
                  "%zu fused, %.1f%% / %.1f%% of points within 5 / 10 cm, "
                  "%.1f of %.1f m seen through",
                  r.published, 100.0 * r.coverage.within_5cm, 100.0 * r.coverage.within_10cm,
                  r.seen.seen_through_m, r.seen.published_m);
    out << "<g transform=\"translate(" << 10 + k * panel << ",56)\">\n"
        << "<text x=\"0\" y=\"-30\">" << title << "</text>\n"
        << "<text x=\"0\" y=\"-12\">" << figures << "</text>\n"
        << "<clipPath id=\"panel" << k << "\"><rect width=\"" << w << "\" height=\"" << h
        << "\"/></clipPath>\n"
        << "<rect width=\"" << w << "\" height=\"" << h << "\" fill=\"none\" stroke=\"#ccc\"/>\n"
        << "<g clip-path=\"url(#panel" << k << ")\">\n"
        << "<path fill=\"#bfe8b0\" d=\"" << open_cells << "\"/>\n"
        << "<path fill=\"#9ab\" fill-opacity=\"0.5\" d=\"" << dots << "\"/>\n"
        << "<path fill=\"none\" stroke=\"#c22\" stroke-width=\"2\" stroke-linecap=\"round\" d=\"";
    for (const Segment2& s : r.segments) {
      char buf[96];
      std::snprintf(buf, sizeof(buf), "M%.1f %.1fL%.1f %.1f", (s.a.x() - lo.x()) * scale,
                    h - (s.a.y() - lo.y()) * scale, (s.b.x() - lo.x()) * scale,
                    h - (s.b.y() - lo.y()) * scale);
      out << buf;
    }
    // Retired walls (seen through by the fusion's own evidence), dashed blue.
    out << "\"/>\n<path fill=\"none\" stroke=\"#26c\" stroke-width=\"2\" "
           "stroke-dasharray=\"4 3\" d=\"";
    for (const Segment2& s : r.retired_segments) {
      char buf[96];
      std::snprintf(buf, sizeof(buf), "M%.1f %.1fL%.1f %.1f", (s.a.x() - lo.x()) * scale,
                    h - (s.a.y() - lo.y()) * scale, (s.b.x() - lo.x()) * scale,
                    h - (s.b.y() - lo.y()) * scale);
      out << buf;
    }
    // The stretches on seen-through cells, over the segments.
    out << "\"/>\n<path fill=\"none\" stroke=\"#000\" stroke-width=\"3\" d=\"";
    for (const Segment2& s : r.segments) {
      const int steps = std::max(1, static_cast<int>(std::ceil(s.length() / 0.02)));
      for (int i = 0; i < steps; ++i) {
        const Vec2 p = s.a + ((i + 0.5) / steps) * (s.b - s.a);
        if (!seen.SeenThrough(p)) continue;
        const Vec2 a = to_px(s.a + (static_cast<double>(i) / steps) * (s.b - s.a));
        const Vec2 b = to_px(s.a + ((i + 1.0) / steps) * (s.b - s.a));
        char buf[96];
        std::snprintf(buf, sizeof(buf), "M%.1f %.1fL%.1f %.1f", a.x(), a.y(), b.x(), b.y());
        out << buf;
      }
    }
    out << "\"/>\n</g>\n</g>\n";
  }
  out << "</svg>\n";
  return static_cast<bool>(out);
}

struct Row {
  std::string log;
  size_t scans = 0, points = 0, raw = 0;
  double read_s = 0.0, extract_s = 0.0;
  RunResult off, on;
};

std::string Table(const std::vector<Row>& rows) {
  std::ostringstream t;
  t << "| log | scans | valid points | raw lines | method | fused (published) | clusters | retired "
       "| "
       "identical pairs | within 5 cm | within 10 cm | seen-through m / published m | "
       "engine s | raw lines/s |\n"
    << "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  char buf[512];
  for (const Row& r : rows) {
    for (int k = 0; k < 2; ++k) {
      const RunResult& run = k == 0 ? r.off : r.on;
      std::snprintf(
          buf, sizeof(buf),
          "| %s | %zu | %zu | %zu | %s | %zu | %zu | %zu | %zu | %.1f%% | %.1f%% | %.1f / %.1f | "
          "%.3f | "
          "%.0f |\n",
          r.log.c_str(), r.scans, r.points, r.raw, k == 0 ? "paper" : "default", run.published,
          run.clusters, run.retired, run.identical_pairs, 100.0 * run.coverage.within_5cm,
          100.0 * run.coverage.within_10cm, run.seen.seen_through_m, run.seen.published_m,
          run.engine_s, static_cast<double>(r.raw) / run.engine_s);
      t << buf;
    }
  }
  return t.str();
}

}  // namespace
}  // namespace mapd::bench

int main(int argc, char** argv) {
  using namespace mapd::bench;  // NOLINT: a benchmark's main
  std::string data_dir = MAPD_SOURCE_DIR "/../shared/data/laser";
  std::string docs_dir = MAPD_SOURCE_DIR "/docs";
  bool write = true;
  mapd::fusion::FusionParams on;  // the defaults, guard included, in the exact (reference) mode
  on.mode =
      mapd::fusion::FusionMode::kExact;  // docs/fusion-real-data.md; bounded: fusion_modes_bench
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--data") && i + 1 < argc) {
      data_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--docs") && i + 1 < argc) {
      docs_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--bounded")) {
      on.mode = mapd::fusion::FusionMode::kBounded;  // mapd's mode, its cost caps included
    } else if (!std::strcmp(argv[i], "--max-component-nodes") && i + 1 < argc) {
      on.max_component_nodes = static_cast<uint32_t>(std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--no-write")) {
      write = false;
    } else if (!std::strcmp(argv[i], "--guard-rms") && i + 1 < argc) {
      on.chain_max_rms_m = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--guard-ratio") && i + 1 < argc) {
      on.chain_max_sse_ratio = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--wall-offset") && i + 1 < argc) {
      on.wall_offset_m = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--occluded-gap") && i + 1 < argc) {
      on.wall_occluded_gap_m = std::atof(argv[++i]);  // 0: no free-space evidence
    } else if (!std::strcmp(argv[i], "--consolidate") && i + 1 < argc) {
      on.consolidate = std::atoi(argv[++i]) != 0;
    } else if (!std::strcmp(argv[i], "--free-min-count") && i + 1 < argc) {
      on.wall_free_min_count = static_cast<uint32_t>(std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--occluded-ratio") && i + 1 < argc) {
      on.wall_occluded_gap_ratio = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: %s [--data DIR] [--docs DIR] [--no-write] [--bounded] "
                   "[--max-component-nodes N] [--guard-rms M] "
                   "[--guard-ratio R] [--wall-offset M] [--occluded-gap M] [--occluded-ratio R] "
                   "[--consolidate 0|1] [--free-min-count N]\n",
                   argv[0]);
      return 2;
    }
  }
  if (const mapd::Status s = on.Validate(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 2;
  }
  // The paper's method: no chain guard, no wall consolidation.
  mapd::fusion::FusionParams off = on;
  off.chain_max_rms_m = 0.0;
  off.consolidate = false;
  off.wall_occluded_gap_m = 0.0;

  std::vector<Row> rows;
  for (const LaserLogSpec& spec : LaserLogs()) {
    Row row;
    row.log = spec.name;
    auto t0 = std::chrono::steady_clock::now();
    mapd::StatusOr<std::vector<LaserScan>> scans = ReadCarmenLaserLog(data_dir + "/" + spec.file);
    if (!scans.ok()) {
      std::fprintf(stderr, "%s\n", scans.status().ToString().c_str());
      return 1;
    }
    auto t1 = std::chrono::steady_clock::now();
    std::vector<ScanLines> lines;
    for (const LaserScan& scan : *scans) lines.push_back(ExtractLaserLines(scan, spec.max_range_m));
    auto t2 = std::chrono::steady_clock::now();
    row.read_s = std::chrono::duration<double>(t1 - t0).count();
    row.extract_s = std::chrono::duration<double>(t2 - t1).count();
    row.scans = lines.size();
    for (const ScanLines& s : lines) {
      row.points += s.points.size();
      row.raw += s.lines.size();
    }
    std::vector<BeamFan> fans;
    for (const ScanLines& s : lines) fans.push_back({s.sensor_xy_m, &s.points});
    const SeenThroughGrid seen(fans);
    row.off = Fuse(lines, seen, off);
    row.on = Fuse(lines, seen, on);
    std::printf("%s: %zu scans, %zu points, %zu raw lines (read %.2f s, extract %.2f s)\n",
                spec.name, row.scans, row.points, row.raw, row.read_s, row.extract_s);
    std::printf(
        "  default: %zu walls retired (seen through since last seen), %.1f m, of which %.1f m "
        "lie on cells the beams passed through (this bench's measure)\n",
        row.on.retired, row.on.retired_seen.published_m, row.on.retired_seen.seen_through_m);
    std::fflush(stdout);
    if (write) {
      const std::string svg = docs_dir + "/fusion-laser-" + spec.name + ".svg";
      if (!WriteSvg(svg, spec.name, lines, seen, row.off, row.on)) {
        std::fprintf(stderr, "cannot write %s\n", svg.c_str());
        return 1;
      }
    }
    rows.push_back(row);
  }
  const std::string table = Table(rows);
  std::printf("\n%s", table.c_str());
  return 0;
}
