#include "learner/data_parallel.h"

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <thread>

#include <nlohmann/json.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"

namespace modskill::learner {
namespace {

using Clock = std::chrono::steady_clock;

std::chrono::milliseconds Millis(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
}

std::string FirstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

std::vector<uint8_t> Bytes(const std::string& text) { return std::vector<uint8_t>(text.begin(), text.end()); }
std::string Text(const std::vector<uint8_t>& bytes) { return std::string(bytes.begin(), bytes.end()); }

// "host:port" or "[v6]:port" -> host and port; INVALID_ARGUMENT naming --rendezvous otherwise.
absl::StatusOr<std::pair<std::string, int>> ParseRendezvous(const std::string& address) {
  const size_t colon = address.rfind(':');
  std::string host = colon == std::string::npos ? "" : address.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  int port = 0;
  if (host.empty() || !absl::SimpleAtoi(address.substr(colon + 1), &port) || port < 1 || port > 65535) {
    return absl::InvalidArgumentError(absl::StrCat("--rendezvous ", address.substr(0, 128),
                                                   ": not host:port with a port in [1, 65535] (rank 0's address)"));
  }
  return std::make_pair(host, port);
}

bool IsLoopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

// Gloo's own sockets: on the loopback when the group is (tests, one machine), else on the address
// this machine's name resolves to, or GLOO_SOCKET_IFNAME's interface as in PyTorch.
std::shared_ptr<::gloo::transport::Device> GlooDevice(const std::string& rendezvous_host) {
  if (const char* interface = std::getenv("GLOO_SOCKET_IFNAME"); interface != nullptr && *interface != '\0') {
    return c10d::ProcessGroupGloo::createDeviceForInterface(interface);
  }
  if (IsLoopback(rendezvous_host)) return c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1");
  return c10d::ProcessGroupGloo::createDefaultDevice();
}

std::string RankKey(const std::string& stage, int rank) { return absl::StrCat(stage, "/", rank); }

}  // namespace

absl::Status ValidateDataParallelOptions(const DataParallelOptions& options) {
  if (options.world_size < 1) {
    return absl::InvalidArgumentError(absl::StrCat("--world_size: ", options.world_size, " must be >= 1"));
  }
  if (options.rank < 0 || options.rank >= options.world_size) {
    return absl::InvalidArgumentError(absl::StrCat("--rank: ", options.rank, " is outside [0, --world_size ",
                                                   options.world_size, ")"));
  }
  if (options.world_size == 1) return absl::OkStatus();
  if (options.rendezvous.empty()) {
    return absl::InvalidArgumentError("--rendezvous: required with --world_size > 1 (rank 0's host:port)");
  }
  if (auto parsed = ParseRendezvous(options.rendezvous); !parsed.ok()) return parsed.status();
  for (const auto& [flag, value] : {std::pair<const char*, double>{"rendezvous_timeout_s", options.rendezvous_timeout_s},
                                    {"collective_timeout_s", options.collective_timeout_s}}) {
    if (!(value > 0 && value <= 86400)) {
      return absl::InvalidArgumentError(absl::StrCat("--", flag, ": ", value, " must be in (0, 86400] s"));
    }
  }
  return absl::OkStatus();
}

DataParallel::DataParallel(const DataParallelOptions& options, c10::intrusive_ptr<c10d::Store> store)
    : options_(options), store_(std::move(store)) {}

DataParallel::~DataParallel() {
  group_.reset();
  store_.reset();
}

absl::StatusOr<std::unique_ptr<DataParallel>> DataParallel::Join(const DataParallelOptions& options) {
  if (absl::Status status = ValidateDataParallelOptions(options); !status.ok()) return status;
  const auto [host, port] = *ParseRendezvous(options.rendezvous);
  c10d::TCPStoreOptions store_options;
  store_options.port = static_cast<uint16_t>(port);
  store_options.isServer = options.rank == 0;
  store_options.waitWorkers = false;  // PostAndWait below waits, naming the ranks that are missing
  store_options.timeout = Millis(options.rendezvous_timeout_s);
  c10::intrusive_ptr<c10d::Store> store;
  try {
    // Rank 0 listens on every interface and reaches its own store on the loopback (its service
    // name may not resolve before it is ready).
    store = c10::make_intrusive<c10d::TCPStore>(options.rank == 0 ? "127.0.0.1" : host, store_options);
  } catch (const std::exception& e) {
    return absl::UnavailableError(absl::StrCat(
        "--rendezvous ", options.rendezvous, ": ",
        options.rank == 0 ? absl::StrCat("rank 0 cannot host the store on port ", port)
                          : absl::StrCat("rank ", options.rank, " cannot reach rank 0's store within ",
                                         options.rendezvous_timeout_s, " s (--rendezvous_timeout_s)"),
        ": ", FirstLine(e.what())));
  }
  std::unique_ptr<DataParallel> group(new DataParallel(options, std::move(store)));
  if (absl::Status status = group->PostAndWait("joined", "", options.rendezvous_timeout_s); !status.ok()) return status;
  try {
    auto gloo_options = c10d::ProcessGroupGloo::Options::create(Millis(options.collective_timeout_s));
    gloo_options->devices.push_back(GlooDevice(host));
    gloo_options->threads = 1;
    group->group_ = c10::make_intrusive<c10d::ProcessGroupGloo>(group->store_, options.rank, options.world_size,
                                                                 gloo_options);
  } catch (const std::exception& e) {
    return absl::UnavailableError(absl::StrCat("--rendezvous ", options.rendezvous, ": rank ", options.rank,
                                               " cannot connect to the other ranks: ", FirstLine(e.what())));
  }
  return group;
}

absl::Status DataParallel::PostAndWait(const std::string& stage, const std::string& value, double timeout_s) {
  const absl::Time deadline = absl::Now() + absl::Seconds(timeout_s);
  try {
    store_->set(RankKey(stage, rank()), Bytes(value));
    while (true) {
      std::vector<int> missing;
      for (int r = 0; r < world_size(); ++r) {
        if (r != rank() && store_->check({RankKey("failed", r)})) {
          return absl::FailedPreconditionError(
              absl::StrCat("rank ", r, " failed: ", Text(store_->get(RankKey("failed", r)))));
        }
        if (!store_->check({RankKey(stage, r)})) missing.push_back(r);
      }
      if (missing.empty()) return absl::OkStatus();
      if (absl::Now() > deadline) {
        return absl::UnavailableError(absl::StrCat("--rendezvous ", options_.rendezvous, ": rank(s) ",
                                                   absl::StrJoin(missing, ", "), " of --world_size ", world_size(),
                                                   " did not reach '", stage, "' within ", timeout_s, " s"));
      }
      absl::SleepFor(absl::Milliseconds(20));
    }
  } catch (const std::exception& e) {
    return absl::UnavailableError(absl::StrCat("--rendezvous ", options_.rendezvous,
                                               ": lost rank 0's store (rank 0 stopped?): ", FirstLine(e.what())));
  }
}

absl::Status DataParallel::CheckSettingsAgree(const std::string& stage, const std::vector<SharedSetting>& settings,
                                              double timeout_s) {
  nlohmann::json mine = nlohmann::json::object();
  for (const auto& [name, value] : settings) mine[name] = value;
  if (absl::Status status = PostAndWait(stage, mine.dump(), timeout_s); !status.ok()) return status;
  std::vector<nlohmann::json> all;
  try {
    for (int r = 0; r < world_size(); ++r) all.push_back(nlohmann::json::parse(Text(store_->get(RankKey(stage, r)))));
  } catch (const std::exception& e) {
    return absl::UnavailableError(absl::StrCat("--rendezvous ", options_.rendezvous, ": reading the ranks' ", stage,
                                               ": ", FirstLine(e.what())));
  }
  // Every rank compares every rank with rank 0 in the same order, so all report the same field.
  for (int r = 1; r < world_size(); ++r) {
    for (const auto& [name, value] : all[0].items()) {
      const std::string theirs = all[r].contains(name) ? all[r][name].get<std::string>() : "(none)";
      if (theirs != value.get<std::string>()) {
        return absl::FailedPreconditionError(absl::StrCat("--", name, ": rank 0 has ", value.get<std::string>(),
                                                          ", rank ", r, " has ", theirs, " (", stage,
                                                          ": every rank must run with the same)"));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status DataParallel::Run(const char* operation, const std::function<void()>& collective, int64_t bytes) {
  const auto start = Clock::now();
  try {
    collective();
  } catch (const std::exception& e) {
    return absl::UnavailableError(absl::StrCat(
        "data-parallel ", operation, " failed on rank ", rank(), " of ", world_size(), " (--rendezvous ",
        options_.rendezvous, ", --collective_timeout_s ", options_.collective_timeout_s, "): ", DiagnoseOthers(),
        " [", FirstLine(e.what()), "]; restart every rank with --resume to continue from rank 0's last checkpoint"));
  }
  collective_seconds_ += std::chrono::duration<double>(Clock::now() - start).count();
  collective_bytes_ += bytes;
  return absl::OkStatus();
}

absl::Status DataParallel::AllReduce(std::vector<at::Tensor>& tensors, bool minimum, const char* operation) {
  c10d::AllreduceOptions reduce;
  reduce.reduceOp = minimum ? c10d::ReduceOp::MIN : c10d::ReduceOp::SUM;
  int64_t bytes = 0;
  for (const at::Tensor& t : tensors) bytes += t.numel() * t.element_size();
  return Run(operation, [&] { group_->allreduce(tensors, reduce)->wait(); }, bytes);
}

absl::StatusOr<bool> DataParallel::AverageGradients(const std::vector<torch::Tensor>& params, bool finite) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> flat;
  flat.reserve(params.size() + 1);
  for (const torch::Tensor& p : params) {
    const bool use = finite && p.grad().defined();
    flat.push_back(use ? p.grad().reshape({-1}).to(torch::kFloat32) : torch::zeros({p.numel()}));
  }
  // The last element counts the ranks whose loss was finite.
  flat.push_back(torch::full({1}, finite ? 1.0f : 0.0f));
  std::vector<at::Tensor> buffer = {torch::cat(flat)};
  if (absl::Status status = AllReduce(buffer, /*minimum=*/false, "gradient all-reduce"); !status.ok()) return status;
  const torch::Tensor& sum = buffer[0];
  if (sum[-1].item<float>() < static_cast<float>(world_size())) return false;
  const torch::Tensor mean = sum / static_cast<float>(world_size());
  int64_t offset = 0;
  for (const torch::Tensor& p : params) {
    if (p.grad().defined()) p.mutable_grad().copy_(mean.slice(0, offset, offset + p.numel()).view_as(p));
    offset += p.numel();
  }
  return true;
}

absl::Status DataParallel::MergeRunningStats(RunningMeanStdImpl& stats, const torch::Tensor& batch) {
  torch::NoGradGuard no_grad;
  const int64_t D = stats.size();
  torch::Tensor packed = torch::zeros({1 + 2 * D}, torch::kFloat64);
  if (batch.size(0) > 0) {
    const RunningMeanStdImpl::Moments moments = stats.BatchMoments(batch);
    packed[0] = moments.count;
    packed.slice(0, 1, 1 + D).copy_(moments.mean);
    packed.slice(0, 1 + D).copy_(moments.var);
  }
  std::vector<std::vector<at::Tensor>> gathered(1);
  for (int r = 0; r < world_size(); ++r) gathered[0].push_back(torch::empty_like(packed));
  std::vector<at::Tensor> input = {packed};
  if (absl::Status status = Run("statistics all-gather", [&] { group_->allgather(gathered, input)->wait(); },
                                packed.numel() * 8);
      !status.ok()) {
    return status;
  }
  // The same sums in the same (rank) order on every rank: identical statistics everywhere.
  RunningMeanStdImpl::Moments all;
  for (const at::Tensor& rank_moments : gathered[0]) {
    all = RunningMeanStdImpl::Combine(
        all, {rank_moments[0].item<double>(), rank_moments.slice(0, 1, 1 + D), rank_moments.slice(0, 1 + D)});
  }
  stats.Merge(all);
  return absl::OkStatus();
}

absl::Status DataParallel::Broadcast(std::string* bytes) {
  std::vector<at::Tensor> size = {torch::full({1}, static_cast<int64_t>(bytes->size()), torch::kInt64)};
  if (absl::Status status = Run("broadcast", [&] { group_->broadcast(size)->wait(); }, 8); !status.ok()) return status;
  const int64_t n = size[0].item<int64_t>();
  std::vector<at::Tensor> data = {torch::empty({n}, torch::kUInt8)};
  if (rank() == 0) std::memcpy(data[0].data_ptr<uint8_t>(), bytes->data(), n);
  if (absl::Status status = Run("broadcast", [&] { group_->broadcast(data)->wait(); }, n); !status.ok()) return status;
  if (rank() != 0) bytes->assign(reinterpret_cast<const char*>(data[0].data_ptr<uint8_t>()), n);
  return absl::OkStatus();
}

absl::Status DataParallel::AllReduceSum(std::vector<double>* values) {
  std::vector<at::Tensor> buffer = {torch::tensor(*values, torch::kFloat64)};
  if (absl::Status status = AllReduce(buffer, /*minimum=*/false, "all-reduce"); !status.ok()) return status;
  for (size_t i = 0; i < values->size(); ++i) (*values)[i] = buffer[0][i].item<double>();
  return absl::OkStatus();
}

absl::StatusOr<double> DataParallel::AllReduceMin(double value) {
  std::vector<at::Tensor> buffer = {torch::full({1}, value, torch::kFloat64)};
  if (absl::Status status = AllReduce(buffer, /*minimum=*/true, "all-reduce"); !status.ok()) return status;
  return buffer[0].item<double>();
}

void DataParallel::MarkIteration(int iteration) {
  iteration_ = iteration;
  try {
    store_->set(RankKey("iteration", rank()), Bytes(std::to_string(iteration)));
  } catch (const std::exception&) {
    // The next collective fails too, and says why.
  }
}

void DataParallel::ReportFailure(const absl::Status& status) {
  try {
    store_->set(RankKey("failed", rank()), Bytes(std::string(status.message())));
    if (rank() != 0) return;
    // The store goes when rank 0 does: give the others a moment to read why.
    const absl::Time deadline = absl::Now() + absl::Seconds(5);
    for (int r = 1; r < world_size() && absl::Now() < deadline; ++r) {
      while (!store_->check({RankKey("failed", r)}) && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
    }
  } catch (const std::exception&) {
    // Nothing more to tell anyone.
  }
}

std::string DataParallel::DiagnoseOthers() {
  std::vector<std::string> findings;
  try {
    store_->setTimeout(std::chrono::seconds(5));
    for (int r = 0; r < world_size(); ++r) {
      if (r == rank()) continue;
      if (store_->check({RankKey("failed", r)})) {
        findings.push_back(absl::StrCat("rank ", r, " failed: ", Text(store_->get(RankKey("failed", r)))));
        continue;
      }
      int at = -1;
      if (store_->check({RankKey("iteration", r)})) (void)absl::SimpleAtoi(Text(store_->get(RankKey("iteration", r))), &at);
      if (at < iteration_) {
        findings.push_back(absl::StrCat("rank ", r, " stopped answering (its last update began at iteration ", at + 1,
                                        ", this rank's at ", iteration_ + 1, ")"));
      }
    }
  } catch (const std::exception& e) {
    return absl::StrCat("rank 0, which hosts the store at ", options_.rendezvous, ", stopped answering");
  }
  if (findings.empty()) return "no rank reported an error (a rank died or stalled in this collective)";
  return absl::StrJoin(findings, "; ");
}

}  // namespace modskill::learner
