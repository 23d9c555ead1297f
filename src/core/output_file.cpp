#include "implicit/core/output_file.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit {
namespace {

// Files being written, for a signal handler: fixed storage, since a handler may only read memory
// and call async-signal-safe functions (unlink, write, _exit).
constexpr int kPendingSlots = 64;
constexpr std::size_t kPendingPathBytes = 4096;
char pending_paths[kPendingSlots][kPendingPathBytes];
std::atomic<bool> pending_used[kPendingSlots];
std::atomic<int> outputs_completed{0};

std::mutex committed_mutex;
std::vector<std::filesystem::path> committed_paths;

int register_pending(const std::filesystem::path& p) {
  const std::string s = p.string();
  if (s.size() >= kPendingPathBytes) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    bool expected = false;
    if (!pending_used[i].load() && pending_used[i].compare_exchange_strong(expected, true)) {
      std::copy(s.c_str(), s.c_str() + s.size() + 1, pending_paths[i]);
      return i;
    }
  }
  return -1;  // more than kPendingSlots at once: that file may remain after a signal
}

void release_pending(int slot) {
  if (slot >= 0) pending_used[slot].store(false);
}

// The gzip stream of `text` into `file`; false when any step failed.
bool write_gzip(const std::filesystem::path& file, const std::string& text) {
  gzFile f = gzopen(file.c_str(), "wb9");
  if (f == nullptr) return false;
  const int wrote = text.empty() ? 0 : gzwrite(f, text.data(), static_cast<unsigned>(text.size()));
  const int closed = gzclose(f);
  return wrote == static_cast<int>(text.size()) && closed == Z_OK;
}

}  // namespace

OutputFile::OutputFile(std::filesystem::path path, Mode mode, std::string flag)
    : path_(std::move(path)), flag_(std::move(flag)), mode_(mode) {
  // Same folder, so that the rename is atomic; the pid keeps concurrent runs apart.
  temporary_ = path_;
  temporary_ += fmt::format(".tmp{}", ::getpid());
  gzip_ = path_.extension() == ".gz";
  require(!(gzip_ && mode == Mode::kAppend),
          "OutputFile: expected a plain file to append to, got '{}' (gzip)", path_.string());
  std::error_code ec;
  fresh_ = !std::filesystem::exists(path_, ec);
  if (mode == Mode::kAppend && !fresh_)
    std::filesystem::copy_file(path_, temporary_, std::filesystem::copy_options::overwrite_existing,
                               ec);
  slot_ = register_pending(temporary_);
  if (gzip_) {
    out_ = std::make_unique<std::ostringstream>();  // compressed into the file by commit()
    return;
  }
  auto file = std::make_unique<std::ofstream>(
      temporary_, mode == Mode::kAppend && !fresh_ ? std::ios::app : std::ios::trunc);
  if (!file->is_open())
    open_error_ = fmt::format("a folder where {} cannot be created ({})",
                              temporary_.filename().string(), std::strerror(errno));
  out_ = std::move(file);
}

OutputFile::~OutputFile() {
  if (committed_) return;
  out_.reset();
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
  release_pending(slot_);
}

std::ostream& OutputFile::stream() { return *out_; }

void OutputFile::fail(const std::string& what) {
  out_.reset();
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
  release_pending(slot_);
  slot_ = -1;
  committed_ = true;  // nothing left for the destructor
  throw InvalidArgument(fmt::format("{}{}{}: expected a writable output file, got {}", flag_,
                                    flag_.empty() ? "" : ": ", path_.string(), what));
}

void OutputFile::commit() {
  require(!committed_, "OutputFile: {} was committed already", path_.string());
  if (!open_error_.empty()) fail(open_error_);
  out_->flush();
  if (gzip_) {
    if (!write_gzip(temporary_, static_cast<std::ostringstream&>(*out_).str()))
      fail(fmt::format("a failed write ({})", std::strerror(errno)));
  } else {
    auto& file = static_cast<std::ofstream&>(*out_);
    const bool written = static_cast<bool>(file);
    file.close();
    if (!written || file.fail()) fail("a failed write");
  }
  std::error_code ec;
  std::filesystem::rename(temporary_, path_, ec);
  if (ec) fail(fmt::format("a failed rename ({})", ec.message()));
  committed_ = true;
  release_pending(slot_);
  if (mode_ == Mode::kRecord) return;
  ++outputs_completed;
  std::lock_guard lock(committed_mutex);
  committed_paths.push_back(path_);
}

void write_output_file(const std::filesystem::path& path, std::string_view text,
                       const std::string& flag) {
  OutputFile out(path, OutputFile::Mode::kReplace, flag);
  out.stream().write(text.data(), static_cast<std::streamsize>(text.size()));
  out.commit();
}

UnfinishedOutput::UnfinishedOutput(const std::filesystem::path& path)
    : slot_(register_pending(path)) {}

UnfinishedOutput::~UnfinishedOutput() { release_pending(slot_); }

int remove_unfinished_outputs() noexcept {
  int removed = 0;
  for (int i = 0; i < kPendingSlots; ++i)
    if (pending_used[i].load() && ::unlink(pending_paths[i]) == 0) ++removed;
  return removed;
}

int completed_outputs() noexcept { return outputs_completed.load(); }

std::vector<std::filesystem::path> committed_output_paths() {
  std::lock_guard lock(committed_mutex);
  return committed_paths;
}

}  // namespace implicit
