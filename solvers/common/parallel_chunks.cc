#include <calib/solvers/common/parallel_chunks.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

namespace calib {
namespace parallel_internal {
namespace {

// A helper keeps polling this long after a pass before it sleeps: a calibration's passes follow
// each other within tens of µs, and a sleeping thread takes about 20 µs to wake.
constexpr auto kPoll = std::chrono::microseconds(50);

struct Job {
  void (*run)(const void*, int);
  const void* context;
  int chunks;
  int helpers;                   // At most this many helpers join.
  std::atomic<int> next{0};      // The next chunk to claim.
  std::atomic<int> finished{0};  // Chunks done.
  std::atomic<int> users{0};     // Helpers inside the job.
};

void Claim(Job* job) {
  for (int c = job->next.fetch_add(1); c < job->chunks; c = job->next.fetch_add(1)) {
    job->run(job->context, c);
    job->finished.fetch_add(1, std::memory_order_release);
  }
}

inline void Pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

class Helpers {
 public:
  static Helpers& Get() {
    static Helpers* helpers = new Helpers();  // Never destroyed: its threads live to the exit.
    return *helpers;
  }

  void Run(int chunks, int threads, void (*run)(const void*, int), const void* context) {
    const int helpers =
        std::min(threads - 1, max_helpers_ - occupied_.load(std::memory_order_relaxed));
    if (helpers <= 0 || busy_.exchange(true, std::memory_order_acquire)) {
      for (int c = 0; c < chunks; ++c) run(context, c);
      return;
    }
    Job job;
    job.run = run;
    job.context = context;
    job.chunks = chunks;
    job.helpers = helpers;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (; started_ < helpers; ++started_) std::thread([this] { Serve(); }).detach();
      job_ = &job;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    Claim(&job);
    while (job.finished.load(std::memory_order_acquire) < chunks) Pause();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = nullptr;
    }
    // A helper that joined after the last chunk was claimed still reads the job: wait it out.
    while (job.users.load(std::memory_order_acquire) > 0) Pause();
    busy_.store(false, std::memory_order_release);
  }

  void Occupy(int change) { occupied_.fetch_add(change, std::memory_order_relaxed); }

 private:
  Helpers() : max_helpers_(std::max(1u, std::thread::hardware_concurrency()) - 1) {}

  void Serve() {
    uint64_t seen = generation_.load(std::memory_order_acquire);
    for (;;) {
      const auto until = std::chrono::steady_clock::now() + kPoll;
      while (occupied_.load(std::memory_order_relaxed) == 0 &&
             generation_.load(std::memory_order_acquire) == seen &&
             std::chrono::steady_clock::now() < until) {
        Pause();
      }
      Job* job = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_relaxed) != seen; });
        seen = generation_.load(std::memory_order_relaxed);
        if (job_ != nullptr && job_->users.load(std::memory_order_relaxed) < job_->helpers) {
          job = job_;
          job->users.fetch_add(1, std::memory_order_relaxed);
        }
      }
      if (job == nullptr) continue;
      Claim(job);
      job->users.fetch_sub(1, std::memory_order_release);
    }
  }

  const int max_helpers_;
  std::atomic<int> occupied_{0};   // Cores busy with other work (OccupiedCore).
  std::atomic<bool> busy_{false};  // A pass holds the helpers.
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<uint64_t> generation_{0};  // Written under mutex_.
  Job* job_ = nullptr;                   // Under mutex_.
  int started_ = 0;                      // Helper threads, under mutex_.
};

}  // namespace

void RunChunks(int chunks, int threads, void (*run)(const void* context, int chunk),
               const void* context) {
  Helpers::Get().Run(chunks, threads, run, context);
}

}  // namespace parallel_internal

OccupiedCore::OccupiedCore() { parallel_internal::Helpers::Get().Occupy(1); }
OccupiedCore::~OccupiedCore() { parallel_internal::Helpers::Get().Occupy(-1); }

}  // namespace calib
