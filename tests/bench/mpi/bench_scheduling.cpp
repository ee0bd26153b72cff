// Scheduling overhead of the MPI runner per trial (rkhs/mpi/distributed.hpp). Run it under mpirun:
//
//   mpirun -np 2 --bind-to none build/release/bench/bench_scheduling
//
// (alone it measures rank 0 handing tasks to its own threads). Rank 0 runs the benchmarks and
// the other ranks serve every job it starts.
//   BM_HandOut/T/B:       T tasks that do nothing but return B bytes: the protocol's cost per
//                         task (hand-out, result message, report), as `per_task`.
//   BM_TinyTrials/local:  16 real approximation trials (n = 8) through rkhs::run_with_store on
//                         oneTBB, one process, no store;
//   BM_TinyTrials/mpi:    the same trials through distributed::run_with_store: the difference
//                         is what distribution costs a real trial (serialisation included).
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <optional>
#include <sstream>

#include "rkhs/mpi/distributed.hpp"
#include "rkhs/plugin/builtins.hpp"

namespace {

namespace distributed = rkhs::distributed;

const distributed::Session* session = nullptr;

constexpr const char* tiny_study = R"([study]
name = "bench_scheduling"
evaluation_points = 64
metrics = ["gram_condition_number", "l2_error"]
[domain]
radius = 1
[grid]
n = [8]
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 4
[[centres]]
name = "random"
seed = [1, 2, 3, 4, 5, 6, 7, 8]
)";

const rkhs::StudyDefinition& study() {
  static const auto loaded = rkhs::parse_study(tiny_study, "bench_scheduling.toml");
  return loaded;
}

int threads_per_rank() {
  return std::max(1, session->default_threads());
}

// One job of `tasks` empty tasks returning `bytes` bytes, on every rank.
void hand_out(std::size_t tasks, std::size_t bytes) {
  distributed::Job job;
  job.threads = threads_per_rank();
  job.run = [bytes](std::uint64_t) { return std::string(bytes, 'x'); };
  std::size_t reported = 0;
  job.on_report = [&](const distributed::TaskReport&) { ++reported; };
  for (std::uint64_t id = 0; id < tasks; ++id) job.order.push_back(id);
  distributed::distribute(*session, job);
  if (session->is_root() && reported != tasks) throw std::logic_error("tasks lost");
}

void tiny_trials() {
  const auto trials = study().trials();
  rkhs::RunOptions options;
  options.threads = threads_per_rank();
  const auto agreed = distributed::require_same_trials(*session, study(), trials);
  const auto run =
      distributed::run_with_store(*session, study(), trials, agreed, options, nullptr, true);
  if (session->is_root() && run->ran != trials.size()) throw std::logic_error("trials lost");
}

// Rank 0 tells the other ranks what comes next: "hand_out T B", "trials" or "end".
void announce(const std::string& command) {
  session->broadcast(command);
}

void BM_HandOut(benchmark::State& state) {
  const auto tasks = static_cast<std::size_t>(state.range(0));
  const auto bytes = static_cast<std::size_t>(state.range(1));
  for (auto _ : state) {
    announce(fmt::format("hand_out {} {}", tasks, bytes));
    hand_out(tasks, bytes);
  }
  state.counters["ranks"] = session->size();
  state.counters["per_task"] =
      benchmark::Counter(static_cast<double>(tasks), benchmark::Counter::kIsIterationInvariantRate |
                                                         benchmark::Counter::kInvert);
}
BENCHMARK(BM_HandOut)
    ->Args({256, 0})
    ->Args({256, 1024})
    ->Args({256, 65536})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_TinyTrials_local(benchmark::State& state) {
  const auto trials = study().trials();
  rkhs::RunOptions options;
  options.threads = threads_per_rank();
  for (auto _ : state)
    benchmark::DoNotOptimize(rkhs::run_with_store(study(), trials, options, nullptr, true));
  state.counters["per_trial"] = benchmark::Counter(
      static_cast<double>(trials.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_TinyTrials_local)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_TinyTrials_mpi(benchmark::State& state) {
  for (auto _ : state) {
    announce("trials");
    tiny_trials();
  }
  state.counters["ranks"] = session->size();
  state.counters["per_trial"] = benchmark::Counter(
      static_cast<double>(study().trials().size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_TinyTrials_mpi)->Unit(benchmark::kMillisecond)->UseRealTime();

// The other ranks: serve each announced job until "end".
void serve() {
  for (;;) {
    std::istringstream command(session->broadcast(""));
    std::string what;
    command >> what;
    if (what == "end") return;
    if (what == "trials") {
      tiny_trials();
    } else {
      std::size_t tasks = 0, bytes = 0;
      command >> tasks >> bytes;
      hand_out(tasks, bytes);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  distributed::Session mpi(argc, argv);
  session = &mpi;
  rkhs::freeze_registries();
  if (!mpi.is_root()) {
    serve();
    return 0;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  announce("end");
  return 0;
}
