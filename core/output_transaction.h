// A subcommand's output folder replaced as one transaction: git writes its objects, then moves one ref.
//
//   OutputTransaction outputs(out);                  // lock, clean up after dead runs, private folder beside out
//   write_everything_into(outputs.folder());
//   outputs.commit(previous_run_wrote);              // carry the user's files over, exchange, sync
//
// The outputs are built in a private folder beside `out` ("<parent>/.<name>.run-XXXXXX", mkdtemp: exclusive,
// unguessable) and exchanged with `out` in one step at the end (renameat2 RENAME_EXCHANGE, then the parent is
// synced and the old contents removed; where the file system refuses the exchange, two renames,
// core/atomic_file.h's swap_folder_into_place). So an interruption at any moment (a signal, SIGKILL, power loss,
// a full disk) leaves either the previous complete set or the new complete set in `out`, never a mix. Nothing
// the run did not write is lost: entries of the old `out` that the previous run did not write (a user's notes, a
// foreign trajectory.png) are carried into the new folder as hard links before the exchange. A run that fails
// before commit() leaves `out` as it was, or absent when it was absent.
//
// Concurrency: an advisory lock (flock) on "<parent>/.<name>.lock", beside `out` and never inside the folder that
// is exchanged, holding the holder's pid; a second transaction on the same `out` is refused at once, naming that
// pid. Under the lock, private folders "<parent>/.<name>.run-*" can only be left by dead runs (SIGKILL, power
// loss): they are removed. The lock file itself stays (removing it would race with a run that just opened it).
// Not thread-safe; one transaction per `out` per process.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json_fwd.hpp>

namespace hf {

class OutputTransaction {
 public:
  // Resolves `out` (a link is followed to its folder), refuses one that exists and is not a folder, the current
  // folder or one holding it (the exchange would move the caller's working folder), and "/"; creates the parent
  // when missing; takes the lock; removes private folders of dead runs; creates this run's private folder.
  // Throws hf::Error naming `out`, e.g. "OUT: in use by another run (pid 1234; lock PARENT/.NAME.lock)".
  explicit OutputTransaction(const std::string& out);
  // Without a commit(): removes the private folder; `out` stays as it was. Releases the lock.
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  const std::string& folder() const { return folder_; }  // where the outputs are written
  const std::string& target() const { return out_; }     // `out`, resolved

  // Carries into folder() every entry of the old `out` that folder() does not hold and `previous_run_wrote(name)`
  // denies (hard links; folders are recreated and their files linked), then puts folder() in place of `out`.
  // Throws hf::Error naming `out`; on failure `out` is left as it was.
  void commit(const std::function<bool(const std::string& name)>& previous_run_wrote);

 private:
  std::string out_, folder_;
  int lock_fd_ = -1;
  bool committed_ = false;
};

// The JSON manifest a previous run left in its folder (OUT/report.json, OUT/results.json, ...), for the
// previous_run_wrote functions given to commit(): true with *json set when `path` is a regular file (a link is not
// followed) that parses; false otherwise (absent, a link, a folder, not JSON), when the folder is a user's.
bool read_previous_manifest(const std::string& path, nlohmann::json* json);

}  // namespace hf
