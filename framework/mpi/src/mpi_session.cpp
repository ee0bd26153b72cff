// The MPI side of rkhs/mpi/distributed.hpp: the session and the task hand-out protocol.
//
// Over 500 lines on purpose: both sides of the protocol (coordinate() on rank 0, serve() on the
// others) share its tags, message helpers and timeouts, and are kept in one file so that the
// protocol below can be read, and changed, in one place.
//
// Protocol (tags below), rank 0 coordinating, every rank (rank 0 too) running tasks:
//   worker -> 0  request  int32: how many tasks it takes (threads + 1), sent once
//   0 -> worker  assign   uint64 ids (none: no more tasks for this job)
//   worker -> 0  result   uint64 id, uint8 skipped, payload; asks for one more task
//   both ways    alive    empty: sent by a side that sent nothing else for a while
//   0 -> worker  end      empty: the job is over (or this rank was taken as lost): leave
// Rank 0 answers every request and every result with `assign` until it has no task left or a
// stop is requested; then it answers with an empty `assign` once. When every task is reported
// it sends `end` to every worker, which then leaves. A worker silent for longer than the job's
// rank timeout is taken as lost: its tasks in flight go back to the front of the queue, and
// rank 0 (which always takes tasks itself) or another rank runs them. Under mpirun's default
// a rank that dies ends the whole job anyway; with --enable-recovery the others go on. Only
// the thread that created the Session calls MPI (MPI_THREAD_FUNNELED); oneTBB threads run the
// tasks and queue their results.
//
// The calling threads poll (MPI_Iprobe) rather than block in MPI_Recv, which spins at full
// speed in Open MPI and would take a core from the worker threads: after activity the poll
// interval starts at a few microseconds and doubles up to a millisecond while idle; a finished
// task wakes the thread at once.

#include <fmt/format.h>
#include <mpi.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "rkhs/core/concurrency.hpp"
#include "rkhs/mpi/distributed.hpp"

namespace rkhs::distributed {

namespace {

constexpr int tag_request = 7101, tag_assign = 7102, tag_result = 7103, tag_alive = 7104,
              tag_end = 7105;

// rkhs-study's own communicator (a duplicate of MPI_COMM_WORLD made by the Session): its
// messages can never match those of a library or of other code in the process.
MPI_Comm communicator = MPI_COMM_NULL;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    throw std::runtime_error(std::string(what) + ": " +
                             std::string(text, static_cast<std::size_t>(length)));
  }
}

int byte_count(std::size_t size) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("an MPI message above 2 GiB");
  return static_cast<int>(size);
}

// Receives the message that MPI_Iprobe found, whatever its length.
std::string receive(const MPI_Status& probed) {
  int count = 0;
  check(MPI_Get_count(&probed, MPI_BYTE, &count), "MPI_Get_count");
  std::string bytes(static_cast<std::size_t>(count), '\0');
  check(MPI_Recv(bytes.data(), count, MPI_BYTE, probed.MPI_SOURCE, probed.MPI_TAG, communicator,
                 MPI_STATUS_IGNORE),
        "MPI_Recv");
  return bytes;
}

template <class T>
void append(std::string& bytes, T value) {
  bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
}

template <class T>
T read(const std::string& bytes, std::size_t at) {
  if (at + sizeof(T) > bytes.size()) throw std::runtime_error("a truncated MPI message");
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof value);
  return value;
}

// This rank's worker threads: tasks go in, reports come out (in completion order) to the MPI
// thread, which is woken when one arrives. A runner thread enters a oneTBB arena of `threads`
// slots and runs one consumer loop per slot for the whole job; the consumers take tasks from a
// queue. The runner works in the arena itself, so the tasks progress even before (or without)
// oneTBB's worker threads joining, and handing a task over is one condition-variable signal.
class LocalPool {
 public:
  explicit LocalPool(const Job& job) : job_(job), runner_([this] { run_consumers(); }) {}

  /// Lets the consumers finish the queued tasks, then joins the runner.
  ~LocalPool() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    work_.notify_all();
    runner_.join();
  }

  void submit(std::uint64_t id) {
    ++in_flight_;
    {
      std::lock_guard lock(mutex_);
      queued_.push_back(id);
    }
    work_.notify_one();
  }

  /// The reports that arrived, after waiting up to `wait` for one when there is none.
  std::deque<TaskReport> take(std::chrono::microseconds wait) {
    std::unique_lock lock(mutex_);
    if (done_.empty() && wait.count() > 0)
      ready_.wait_for(lock, wait, [this] { return !done_.empty(); });
    if (error_) std::rethrow_exception(error_);  // a task's `run` broke its contract
    std::deque<TaskReport> out;
    out.swap(done_);
    in_flight_ -= out.size();
    return out;
  }

  /// Drops the tasks not started yet (tasks running finish; their reports are not taken).
  void abandon() {
    std::lock_guard lock(mutex_);
    queued_.clear();
  }

  std::size_t in_flight() const noexcept { return in_flight_; }
  /// Tasks to keep on this rank: one per thread plus one waiting, so that a thread that
  /// finishes starts the next task at once instead of waiting for a message round trip.
  std::size_t capacity() const noexcept { return static_cast<std::size_t>(job_.threads) + 1; }

 private:
  void run_consumers() {
    run_concurrently(static_cast<std::size_t>(job_.threads), job_.threads,
                     [&](std::size_t) { consume(); });
  }

  // Runs queued tasks until the pool is closed and the queue is empty.
  void consume() {
    for (;;) {
      std::uint64_t id = 0;
      {
        std::unique_lock lock(mutex_);
        work_.wait(lock, [this] { return closed_ || !queued_.empty(); });
        if (queued_.empty()) return;
        id = queued_.front();
        queued_.pop_front();
      }
      TaskReport report;
      report.id = id;
      std::exception_ptr error;
      try {
        std::optional<std::string> payload;
        if (!(job_.stop_requested && job_.stop_requested())) payload = job_.run(id);
        report.skipped = !payload;
        if (payload) report.payload = std::move(*payload);
      } catch (...) {
        error = std::current_exception();
      }
      {
        std::lock_guard lock(mutex_);
        if (error && !error_) error_ = error;
        done_.push_back(std::move(report));
      }
      ready_.notify_one();
    }
  }

  const Job& job_;
  std::mutex mutex_;
  std::condition_variable work_, ready_;
  std::deque<std::uint64_t> queued_;
  bool closed_ = false;
  std::deque<TaskReport> done_;
  std::exception_ptr error_;
  std::size_t in_flight_ = 0;  // submitted, report not yet taken (the MPI thread only)
  std::thread runner_;         // last: started once everything above exists
};

// Poll interval: short right after activity, doubling to 1 ms while nothing happens.
class Backoff {
 public:
  std::chrono::microseconds next() {
    const auto wait = wait_;
    wait_ = std::min(wait_ * 2, std::chrono::microseconds(1000));
    return wait;
  }
  void reset() { wait_ = std::chrono::microseconds(4); }

 private:
  std::chrono::microseconds wait_{4};
};

using Clock = std::chrono::steady_clock;

// How often a rank that sent nothing else says it is alive, for a given timeout.
Clock::duration heartbeat_interval(double timeout_seconds) {
  const double seconds = std::clamp(timeout_seconds / 5, 0.05, 5.0);
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

bool silent_for(Clock::time_point since, double timeout_seconds, Clock::time_point now) {
  return timeout_seconds > 0 && now - since > std::chrono::duration<double>(timeout_seconds);
}

// Sends without blocking on a peer that may be gone: true when the message left.
bool try_send(const std::string& bytes, int destination, int tag) {
  return MPI_Send(bytes.data(), byte_count(bytes.size()), MPI_BYTE, destination, tag,
                  communicator) == MPI_SUCCESS;
}

// A worker's message to rank 0; a large one waits for rank 0 to take it, which a rank 0 that
// died never does: then the worker ends with an error instead of waiting for ever.
void send_to_root(const std::string& bytes, int tag, double timeout_seconds) {
  MPI_Request request;
  check(MPI_Isend(bytes.data(), byte_count(bytes.size()), MPI_BYTE, 0, tag, communicator, &request),
        "MPI_Isend");
  const auto start = Clock::now();
  Backoff backoff;
  for (;;) {
    int done = 0;
    check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return;
    if (silent_for(start, timeout_seconds, Clock::now()))
      throw std::runtime_error(fmt::format(
          "rank 0 took no message for {} s (it stopped, or its node did)", timeout_seconds));
    std::this_thread::sleep_for(backoff.next());
  }
}

// Rank 0: hands tasks out and collects their reports; takes a worker that stays silent longer
// than job.rank_timeout_seconds as lost and hands its tasks in flight to the other ranks.
void coordinate(const Session& session, const Job& job, JobStatistics& statistics) {
  LocalPool pool(job);
  const auto ranks = static_cast<std::size_t>(session.size());
  std::deque<std::uint64_t> queue(job.order.begin(), job.order.end());  // not handed out yet
  std::map<std::uint64_t, std::size_t> position;  // in job.order: re-queued tasks keep it
  for (std::size_t k = 0; k < job.order.size(); ++k) position[job.order[k]] = k;
  struct Peer {
    std::vector<std::uint64_t> holding;  // handed out, not yet reported
    bool closed = false;                 // told that no task follows
    bool lost = false;
    Clock::time_point heard, told;  // last message from it, to it
  };
  std::vector<Peer> peers(ranks);
  peers[0].closed = true;  // rank 0 takes its tasks from the queue directly
  for (auto& peer : peers) peer.heard = peer.told = Clock::now();
  const auto interval = heartbeat_interval(job.rank_timeout_seconds);
  bool stopping = false;
  Backoff backoff;

  auto report = [&](TaskReport&& r) {
    auto& holding = peers[static_cast<std::size_t>(r.rank)].holding;
    const auto it = std::find(holding.begin(), holding.end(), r.id);
    if (it == holding.end()) return;  // a task taken back from a rank that was lost
    holding.erase(it);
    if (!r.skipped) ++statistics.ranks[static_cast<std::size_t>(r.rank)].trials;
    job.on_report(r);
  };
  auto skip_queue = [&] {
    for (; !queue.empty(); queue.pop_front()) {
      peers[0].holding.push_back(queue.front());
      report({queue.front(), true, {}, 0});
    }
  };
  auto lose = [&](std::size_t r, const std::string& why) {
    auto& peer = peers[r];
    peer.lost = true;
    session.mark_rank_lost();
    statistics.ranks[r].lost = true;
    std::cerr << fmt::format(
        "rkhs-study: warning: MPI rank {} ({}) {}: taken as lost; its {} trial{} in flight go "
        "to the other ranks\n",
        r, statistics.ranks[r].host, why, peer.holding.size(), peer.holding.size() == 1 ? "" : "s");
    std::sort(peer.holding.begin(), peer.holding.end(),
              [&](auto a, auto b) { return position.at(a) > position.at(b); });
    for (const auto id : peer.holding) queue.push_front(id);  // largest first again
    peer.holding.clear();
    try_send({}, static_cast<int>(r), tag_end);  // in case it is only slow: it leaves
    if (stopping) skip_queue();
  };
  // Answers a rank that can start `wanted` more tasks.
  auto assign = [&](std::size_t r, std::size_t wanted) {
    auto& peer = peers[r];
    if (peer.closed) return;
    std::string ids;
    for (; wanted > 0 && !stopping && !queue.empty(); --wanted, queue.pop_front()) {
      append(ids, queue.front());
      peer.holding.push_back(queue.front());
    }
    if (ids.empty()) peer.closed = true;  // an empty assignment: no more tasks
    if (!try_send(ids, static_cast<int>(r), tag_assign)) lose(r, "cannot be reached");
    peer.told = Clock::now();
  };

  for (;;) {
    bool activity = false;
    if (!stopping && job.stop_requested && job.stop_requested()) {
      stopping = true;
      skip_queue();
    }
    while (!stopping && pool.in_flight() < pool.capacity() && !queue.empty()) {
      peers[0].holding.push_back(queue.front());
      pool.submit(queue.front());
      queue.pop_front();
    }
    int arrived = 0;
    MPI_Status status;
    check(MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, communicator, &arrived, &status), "MPI_Iprobe");
    if (arrived) {
      activity = true;
      const std::string bytes = receive(status);
      const auto r = static_cast<std::size_t>(status.MPI_SOURCE);
      if (!peers[r].lost) {  // a lost rank's late messages are dropped
        peers[r].heard = Clock::now();
        if (status.MPI_TAG == tag_request) {
          assign(r, static_cast<std::size_t>(std::max(read<std::int32_t>(bytes, 0), 1)));
        } else if (status.MPI_TAG == tag_result) {
          report({read<std::uint64_t>(bytes, 0), read<std::uint8_t>(bytes, 8) != 0, bytes.substr(9),
                  status.MPI_SOURCE});
          assign(r, 1);
        } else if (status.MPI_TAG != tag_alive) {
          throw std::runtime_error("an MPI message with an unknown tag");
        }
      }
    }
    const auto now = Clock::now();
    for (std::size_t r = 1; r < ranks; ++r) {
      if (peers[r].lost) continue;
      if (silent_for(peers[r].heard, job.rank_timeout_seconds, now))
        lose(r, fmt::format("sent nothing for {} s", job.rank_timeout_seconds));
      else if (now - peers[r].told > interval) {
        if (!try_send({}, static_cast<int>(r), tag_alive)) lose(r, "cannot be reached");
        peers[r].told = now;
      }
    }
    // Rank 0 counts as closed: it is never lost, so its own tasks are waited for too.
    const bool all_done =
        queue.empty() && std::all_of(peers.begin(), peers.end(), [](const Peer& p) {
          return p.lost || (p.closed && p.holding.empty());
        });
    if (all_done) {
      for (std::size_t r = 1; r < ranks; ++r)
        if (!peers[r].lost) try_send({}, static_cast<int>(r), tag_end);
      return;
    }
    auto finished = pool.take(activity ? std::chrono::microseconds(0) : backoff.next());
    if (!finished.empty()) activity = true;
    for (auto& r : finished) report(std::move(r));
    if (activity) backoff.reset();
  }
}

// Other ranks: ask for tasks, run them, send the results back, until rank 0 says the job is
// over. Rank 0 silent for longer than job.rank_timeout_seconds ends this rank with an error.
void serve(const Job& job) {
  LocalPool pool(job);
  std::string request;
  append(request, static_cast<std::int32_t>(pool.capacity()));
  send_to_root(request, tag_request, job.rank_timeout_seconds);
  const auto interval = heartbeat_interval(job.rank_timeout_seconds);
  auto heard = Clock::now(), told = Clock::now();
  Backoff backoff;
  for (;;) {
    bool activity = false;
    int arrived = 0;
    MPI_Status status;
    check(MPI_Iprobe(0, MPI_ANY_TAG, communicator, &arrived, &status), "MPI_Iprobe");
    if (arrived) {
      activity = true;
      heard = Clock::now();
      const std::string bytes = receive(status);
      if (status.MPI_TAG == tag_end) {
        pool.abandon();  // empty unless rank 0 took this rank as lost
        return;
      }
      if (status.MPI_TAG == tag_assign)
        for (std::size_t at = 0; at + 8 <= bytes.size(); at += 8)
          pool.submit(read<std::uint64_t>(bytes, at));
    }
    auto finished = pool.take(activity ? std::chrono::microseconds(0) : backoff.next());
    for (auto& r : finished) {
      std::string bytes;
      bytes.reserve(9 + r.payload.size());
      append(bytes, r.id);
      append(bytes, static_cast<std::uint8_t>(r.skipped ? 1 : 0));
      bytes += r.payload;
      send_to_root(bytes, tag_result, job.rank_timeout_seconds);
      told = Clock::now();
      activity = true;
    }
    const auto now = Clock::now();
    if (silent_for(heard, job.rank_timeout_seconds, now))
      throw std::runtime_error(fmt::format(
          "rank 0 sent nothing for {} s (it stopped, or its node did)", job.rank_timeout_seconds));
    if (now - told > interval) {
      send_to_root({}, tag_alive, job.rank_timeout_seconds);
      told = now;
    }
    if (activity) backoff.reset();
  }
}

}  // namespace

bool available() noexcept {
  return true;
}

int usable_cpus() noexcept {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0)
    return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, CPU_COUNT(&set));
}

Session::Session(int& argc, char**& argv) {
  int initialised = 0;
  check(MPI_Initialized(&initialised), "MPI_Initialized");
  if (initialised) throw std::runtime_error("MPI is already initialised (one Session per process)");
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw std::runtime_error("the MPI library does not support MPI_THREAD_FUNNELED");
  }
  check(MPI_Comm_dup(MPI_COMM_WORLD, &communicator), "MPI_Comm_dup");
  // Errors are returned, not fatal: a send to a rank that died marks it lost (mpirun
  // --enable-recovery keeps the others running).
  MPI_Comm_set_errhandler(communicator, MPI_ERRORS_RETURN);
  MPI_Comm_rank(communicator, &rank_);
  MPI_Comm_size(communicator, &size_);
  MPI_Comm node;
  MPI_Comm_split_type(communicator, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &ranks_on_node_);
  MPI_Comm_free(&node);
  char name[MPI_MAX_PROCESSOR_NAME];
  int length = 0;
  MPI_Get_processor_name(name, &length);
  host_.assign(name, static_cast<std::size_t>(length));
}

// The communicator is not freed (a collective call, which a lost rank would never join):
// MPI_Finalize releases it.
Session::~Session() {
  if (!rank_lost_) MPI_Finalize();  // see mark_rank_lost()
}

int Session::default_threads() const noexcept {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, std::min(usable_cpus(), hardware / std::max(1, ranks_on_node_)));
}

std::vector<std::string> Session::gather(const std::string& text) const {
  int length = byte_count(text.size());
  std::vector<int> lengths(is_root() ? static_cast<std::size_t>(size_) : 0);
  check(MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, communicator), "MPI_Gather");
  std::vector<int> offsets(lengths.size());
  std::string all;
  if (is_root()) {
    std::size_t total = 0;
    for (std::size_t r = 0; r < lengths.size(); ++r) {
      offsets[r] = byte_count(total);
      total += static_cast<std::size_t>(lengths[r]);
    }
    all.resize(total);
  }
  check(MPI_Gatherv(text.data(), length, MPI_BYTE, all.data(), lengths.data(), offsets.data(),
                    MPI_BYTE, 0, communicator),
        "MPI_Gatherv");
  std::vector<std::string> out;
  for (std::size_t r = 0; r < lengths.size(); ++r)
    out.push_back(
        all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(lengths[r])));
  return out;
}

std::string Session::broadcast(const std::string& value) const {
  int length = is_root() ? byte_count(value.size()) : 0;
  check(MPI_Bcast(&length, 1, MPI_INT, 0, communicator), "MPI_Bcast");
  std::string out = is_root() ? value : std::string(static_cast<std::size_t>(length), '\0');
  check(MPI_Bcast(out.data(), length, MPI_BYTE, 0, communicator), "MPI_Bcast");
  return out;
}

void Session::abort(const std::string& why, int code) const {
  std::cerr << "rkhs-study: rank " << rank_ << ": " << why << "; ending the MPI job\n"
            << std::flush;
  MPI_Abort(MPI_COMM_WORLD, code);
  std::abort();
}

JobStatistics distribute(const Session& session, const Job& job) {
  if (job.threads < 1)
    throw std::invalid_argument("a distributed job needs at least one thread per rank");
  // Who takes part: host and threads of every rank.
  JobStatistics statistics;
  const auto described =
      session.gather(fmt::format("{} {} {}", job.threads, usable_cpus(), session.host()));
  for (std::size_t r = 0; r < described.size(); ++r) {
    std::istringstream in(described[r]);
    RankRecord rank;
    int cpus = 0;
    in >> rank.threads >> cpus >> std::ws;
    std::getline(in, rank.host);
    // A rank bound to fewer cores than it has threads (mpirun binds to a core by default
    // when there are 2 ranks or fewer) runs them in turn.
    if (rank.threads > cpus)
      std::cerr << fmt::format(
          "rkhs-study: warning: MPI rank {} on {} runs {} threads on {} "
          "core{} it is bound to; start mpirun with --bind-to none (or give "
          "each rank as many cores as threads)\n",
          r, rank.host, rank.threads, cpus, cpus == 1 ? "" : "s");
    statistics.ranks.push_back(std::move(rank));
  }
  try {
    if (session.is_root())
      coordinate(session, job, statistics);
    else
      serve(job);
  } catch (const std::exception& e) {
    session.abort(e.what(), 2);
  } catch (...) {
    session.abort("unknown exception", 2);
  }
  return statistics;
}

}  // namespace rkhs::distributed
