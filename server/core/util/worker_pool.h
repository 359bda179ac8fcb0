// A fixed pool of threads that runs one parallel-for at a time; the calling thread works too,
// so a pool of T threads starts T - 1 helpers.
#ifndef MODSKILL_SERVER_CORE_UTIL_WORKER_POOL_H_
#define MODSKILL_SERVER_CORE_UTIL_WORKER_POOL_H_

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace modskill {

class WorkerPool {
 public:
  explicit WorkerPool(int num_threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int num_threads() const { return num_threads_; }
  // Calls work(t) for t in [0, num_threads) with t = 0 on the caller; returns when all are done.
  // `work` must outlive the call; nothing is allocated per call.
  void Run(const std::function<void(int)>& work);

 private:
  void HelperLoop(int thread_index);

  const int num_threads_;
  std::vector<std::thread> helpers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable finished_;
  const std::function<void(int)>* work_ = nullptr;
  uint64_t generation_ = 0;
  int pending_ = 0;
  bool stopping_ = false;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_UTIL_WORKER_POOL_H_
