/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef vuOutput_h
#define vuOutput_h

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vu {
/** An error's text on one line, without the "ITK ERROR: Class(0x...): " prefix of ITK's
 * exception macros (also where it is quoted inside another message). */
std::string
OneLine(std::string text);

/** Writes text to path atomically: to a temporary name beside it, then renamed, so a
 * failure never leaves a half-written file. */
void
WriteTextFileAtomically(const std::string & path, const std::string & text);

/** Pretty JSON to standard output or, when path is not empty, to a file (atomically). */
void
EmitJson(const nlohmann::json & json, const std::string & path);

/** Where a command builds its results: a hidden folder beside the destination,
 * ".NAME.partial-PID", moved into place by Commit() only when every file is complete.
 *
 * Whatever stops the command before Commit() leaves the destination as it was: an error
 * (the destructor removes the folder), SIGINT, SIGTERM, SIGHUP or SIGQUIT (a handler
 * removes it, then the process ends by the same signal). A process killed outright
 * (SIGKILL, power loss) cannot clean up: its staging folder stays hidden beside the
 * destination, which it never touched, and the next command writing to that destination
 * removes the staging folders of processes that no longer run.
 *
 * A Folder destination receives the staged folder itself (renamed in one step when it
 * does not exist or is empty; otherwise its files are replaced one by one). A File
 * destination receives the single file FilePath() names. */
class OutputStaging
{
public:
  enum class Kind
  {
    Folder,
    File
  };
  OutputStaging(const std::filesystem::path & destination, Kind kind);
  ~OutputStaging();
  OutputStaging(const OutputStaging &) = delete;
  OutputStaging &
  operator=(const OutputStaging &) = delete;

  /** The staging folder. */
  const std::filesystem::path &
  Path() const
  {
    return m_Path;
  }
  /** For a File destination: the file to write, inside the staging folder. */
  std::filesystem::path
  FilePath() const;

  /** Throws vu::UsageError naming the folder, the space needed and the space free when the
   * file system of the destination has less than bytes free. */
  void
  RequireSpace(std::uintmax_t bytes) const;

  /** What Commit() does with a Folder destination that exists and holds files: replace
   * the files the staging folder has (MergeFiles), or the whole folder (Replace). */
  enum class Existing
  {
    MergeFiles,
    Replace
  };
  /** Moves the staged result into place; afterwards the destructor leaves it alone. */
  void
  Commit(Existing existing = Existing::MergeFiles);

private:
  std::filesystem::path m_Destination;
  std::filesystem::path m_Path;
  Kind                  m_Kind;
  int                   m_Slot{ -1 };
  bool                  m_Committed{ false };
};

/** Throws vu::UsageError naming what needs the memory, how much, and the process's
 * address-space limit (ulimit -v) when bytes more would not fit under that limit. */
void
RequireMemory(std::uintmax_t bytes, const std::string & what);

/** "12.3 MiB", "1.50 GiB": a size as a person reads it. */
std::string
DescribeBytes(std::uintmax_t bytes);

/** What the command is doing now ("reading", "segmenting" ...), for the message of a
 * failure that cannot say it itself (an allocation that fails). */
void
SetActivity(const std::string & activity);
const std::string &
GetActivity();
/** An output folder written before with the other layout (one sheet's files, named in
 * oneSheetFiles, or a folder sheet-NN per sheet) loses those files, so that nothing stale
 * is mistaken for this run's results. */
void
RemoveOtherLayout(const std::filesystem::path &    output,
                  bool                             folderPerSheet,
                  const std::vector<std::string> & oneSheetFiles);

} // namespace vu

#endif
