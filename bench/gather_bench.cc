// This machine's limit for the hash grid's memory access: random gathers of one table entry (8 bytes: 2 floats,
// the default layout; 16 bytes: 4 floats, the quality layout) from tables of a hash level's size and of all
// levels together, on 1 and 2 threads.
// - latency-bound: each gather's index depends on the value the previous one read (a chain; one miss at a time);
// - bandwidth-bound: independent random indices, summed (as many misses in flight as the core allows);
// - in pairs: the second gather of each pair is the entry beside the first (x and x + 1 of a grid cell share a
//   cache line most of the time), so a pair costs about one miss: the grid's 8 corners are 4 such pairs.
// Prints millions of gathers per second (all threads together) and nanoseconds per gather per thread.
// Usage: gather_bench [GATHERS_PER_THREAD]

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

// A table of `entries` entries of `Width` floats, and per thread its own random entry indices.
template <int Width>
struct Table {
  explicit Table(size_t entries) : values(entries * Width) {
    std::mt19937 random(1);
    // A random cycle through all entries for the chain: the first float of entry i holds the next entry.
    std::vector<uint32_t> order(entries);
    for (size_t i = 0; i < entries; ++i) order[i] = static_cast<uint32_t>(i);
    std::shuffle(order.begin(), order.end(), random);
    for (size_t i = 0; i < entries; ++i) {
      const uint32_t next = order[(i + 1) % entries];
      values[size_t(order[i]) * Width] = static_cast<float>(next);
    }
  }
  size_t entries() const { return values.size() / Width; }
  std::vector<float> values;
};

// Seconds for `gathers` dependent gathers on each of `threads` threads.
template <int Width>
double Chain(const Table<Width>& table, int threads, size_t gathers) {
  std::vector<float> sink(threads);
  const auto start = Clock::now();
  tbb::parallel_for(
      0, threads,
      [&](int t) {
        uint32_t entry = static_cast<uint32_t>(t * 7919 % table.entries());
        for (size_t i = 0; i < gathers; ++i) entry = static_cast<uint32_t>(table.values[size_t(entry) * Width]);
        sink[t] = static_cast<float>(entry);
      },
      tbb::static_partitioner());
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (sink[0] < 0) std::printf("%f", sink[0]);
  return seconds;
}

// Seconds for `gathers` independent gathers (every `pair`-th one beside the previous) on each thread.
template <int Width>
double Independent(const Table<Width>& table, int threads, size_t gathers, bool pairs) {
  std::vector<std::vector<uint32_t>> indices(threads);
  for (int t = 0; t < threads; ++t) {
    std::mt19937 random(100 + t);
    std::uniform_int_distribution<uint32_t> uniform(0, static_cast<uint32_t>(table.entries() - 2));
    indices[t].resize(gathers);
    for (size_t i = 0; i < gathers; ++i) indices[t][i] = pairs && i % 2 == 1 ? indices[t][i - 1] + 1 : uniform(random);
  }
  std::vector<float> sink(threads);
  const auto start = Clock::now();
  tbb::parallel_for(
      0, threads,
      [&](int t) {
        float sum[Width] = {};
        for (const uint32_t entry : indices[t]) {
          const float* value = table.values.data() + size_t(entry) * Width;
          for (int f = 0; f < Width; ++f) sum[f] += value[f];
        }
        sink[t] = sum[0];
      },
      tbb::static_partitioner());
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (sink[0] < 0) std::printf("%f", sink[0]);
  return seconds;
}

template <int Width>
void Measure(size_t entries, size_t gathers) {
  const Table<Width> table(entries);
  for (int threads = 1; threads <= 2; ++threads) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    const auto report = [&](const char* what, double seconds) {
      std::printf("%2d B x 2^%-2d (%5.1f MB)  %d thread%s  %-13s %7.1f M/s  %6.1f ns\n", 4 * Width,
                  static_cast<int>(std::log2(double(entries))), 4.0 * Width * entries / 1e6, threads,
                  threads > 1 ? "s" : " ", what, threads * gathers / seconds / 1e6, seconds / gathers * 1e9);
    };
    Independent(table, threads, gathers / 4, false);  // warm the table and the TLB
    report("latency", Chain(table, threads, gathers / 4) * 4);
    report("bandwidth", Independent(table, threads, gathers, false));
    report("in pairs", Independent(table, threads, gathers, true));
  }
}

}  // namespace

int main(int argc, char** argv) {
  const size_t gathers = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1 << 24;
  // 2^19 entries: one hashed level of the default table size; 2^23: about all sixteen levels together.
  for (const int log2_entries : {16, 19, 23}) {
    Measure<2>(size_t{1} << log2_entries, gathers);
    Measure<4>(size_t{1} << log2_entries, gathers);
  }
  return 0;
}
