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
#include "vuOutput.h"

#include "vuCommands.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <regex>

#include <dirent.h>
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace vu {
std::string
OneLine(std::string text)
{
  for (char & c : text)
  {
    if (c == '\n' || c == '\r')
    {
      c = ' ';
    }
  }
  // itkExceptionMacro prefixes "ITK ERROR: Class(0x...): " and itkGenericExceptionMacro
  // "ITK ERROR: ", also when the text is quoted inside another message: neither tells a
  // user anything.
  static const std::regex prefix("ITK ERROR: ([^( ]*\\(0x[0-9a-fA-F]+\\): )?");
  return std::regex_replace(text, prefix, "");
}

void
WriteTextFileAtomically(const std::string & path, const std::string & text)
{
  const std::string temporary = path + ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out)
    {
      std::remove(temporary.c_str());
      throw UsageError("cannot write " + path + " (is the disk full?)");
    }
  }
  fs::rename(temporary, path);
}

void
EmitJson(const nlohmann::json & json, const std::string & path)
{
  if (path.empty())
  {
    std::cout << json.dump(2) << std::endl;
  }
  else
  {
    WriteTextFileAtomically(path, json.dump(2) + "\n");
  }
}

std::string
DescribeBytes(std::uintmax_t bytes)
{
  char         text[32];
  const double mib = static_cast<double>(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024.0)
  {
    std::snprintf(text, sizeof(text), "%.2f GiB", mib / 1024.0);
  }
  else
  {
    std::snprintf(text, sizeof(text), "%.1f MiB", mib);
  }
  return text;
}

namespace {
std::string g_Activity;

// The staging folders a signal must remove, as plain character arrays: the handler may
// only use what is safe in a signal handler (no allocation, no locks).
constexpr int                                              MaximumStagings = 4;
constexpr size_t                                           MaximumPath = 4096;
std::array<std::array<char, MaximumPath>, MaximumStagings> g_Stagings{};
volatile std::sig_atomic_t                                 g_HandlersInstalled = 0;

// Removes a folder tree with system calls only (openat, getdents64, unlinkat), which are
// async-signal-safe; depth is bounded because staging folders are shallow.
void
RemoveTreeAt(int parent, const char * name, int depth)
{
  const int folder = openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (folder < 0)
  {
    unlinkat(parent, name, 0);
    return;
  }
  char buffer[4096];
  bool removed = true;
  while (removed) // entries removed while listing may hide others: list again
  {
    removed = false;
    lseek(folder, 0, SEEK_SET);
    for (;;)
    {
      const long count = syscall(SYS_getdents64, folder, buffer, sizeof(buffer));
      if (count <= 0)
      {
        break;
      }
      for (long offset = 0; offset < count;)
      {
        // struct linux_dirent64: ino (8), off (8), reclen (2), type (1), name.
        unsigned short length = 0;
        std::memcpy(&length, buffer + offset + 16, sizeof(length));
        const unsigned char type = static_cast<unsigned char>(buffer[offset + 18]);
        const char *        entry = buffer + offset + 19;
        offset += length;
        if (std::strcmp(entry, ".") == 0 || std::strcmp(entry, "..") == 0)
        {
          continue;
        }
        if (type == DT_DIR && depth < 16)
        {
          RemoveTreeAt(folder, entry, depth + 1);
        }
        else
        {
          unlinkat(folder, entry, 0);
        }
        removed = true;
      }
    }
  }
  close(folder);
  unlinkat(parent, name, AT_REMOVEDIR);
}

void
RemoveStagingsOnSignal(int signal)
{
  for (auto & path : g_Stagings)
  {
    if (path[0] != '\0')
    {
      RemoveTreeAt(AT_FDCWD, path.data(), 0);
      path[0] = '\0';
    }
  }
  // End the way the signal would have ended the process.
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

void
InstallSignalHandlers()
{
  if (g_HandlersInstalled)
  {
    return;
  }
  g_HandlersInstalled = 1;
  for (int signal : { SIGINT, SIGTERM, SIGHUP, SIGQUIT })
  {
    struct sigaction action
    {};
    action.sa_handler = RemoveStagingsOnSignal;
    sigemptyset(&action.sa_mask);
    for (int other : { SIGINT, SIGTERM, SIGHUP, SIGQUIT })
    {
      sigaddset(&action.sa_mask, other);
    }
    sigaction(signal, &action, nullptr);
  }
}

int
RegisterStaging(const fs::path & path)
{
  const std::string text = fs::absolute(path).string();
  if (text.size() >= MaximumPath)
  {
    throw UsageError("output path too long: " + text);
  }
  InstallSignalHandlers();
  for (int slot = 0; slot < MaximumStagings; ++slot)
  {
    if (g_Stagings[slot][0] == '\0')
    {
      sigset_t block, previous;
      sigemptyset(&block);
      for (int signal : { SIGINT, SIGTERM, SIGHUP, SIGQUIT })
      {
        sigaddset(&block, signal);
      }
      sigprocmask(SIG_BLOCK, &block, &previous);
      std::memcpy(g_Stagings[slot].data(), text.c_str(), text.size() + 1);
      sigprocmask(SIG_SETMASK, &previous, nullptr);
      return slot;
    }
  }
  return -1;
}

void
UnregisterStaging(int slot)
{
  if (slot >= 0)
  {
    g_Stagings[slot][0] = '\0';
  }
}

// Staging folders ".NAME.partial-PID" beside destination whose process no longer runs.
void
RemoveStaleStagings(const fs::path & parent, const std::string & name)
{
  const std::string prefix = "." + name + ".partial-";
  std::error_code   error;
  for (const auto & entry : fs::directory_iterator(parent, error))
  {
    const std::string candidate = entry.path().filename().string();
    if (candidate.compare(0, prefix.size(), prefix) != 0)
    {
      continue;
    }
    const std::string digits = candidate.substr(prefix.size());
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9)
    {
      continue;
    }
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid != getpid() && kill(pid, 0) != 0 && errno == ESRCH)
    {
      fs::remove_all(entry.path(), error);
    }
  }
}
} // namespace

void
SetActivity(const std::string & activity)
{
  g_Activity = activity;
}

const std::string &
GetActivity()
{
  return g_Activity;
}

OutputStaging::OutputStaging(const fs::path & destination, Kind kind)
  : m_Destination(destination)
  , m_Kind(kind)
{
  fs::path name = destination.filename();
  if (name.empty() || name == "." || name == "..")
  {
    m_Destination = fs::absolute(destination).lexically_normal();
    if (m_Destination.filename().empty())
    {
      m_Destination = m_Destination.parent_path();
    }
    name = m_Destination.filename();
  }
  const fs::path  parent = m_Destination.has_parent_path() ? m_Destination.parent_path() : fs::path(".");
  std::error_code error;
  if (kind == Kind::Folder && fs::exists(m_Destination, error) && !fs::is_directory(m_Destination, error))
  {
    throw UsageError("output " + m_Destination.string() + " exists and is not a directory");
  }
  if (kind == Kind::File && fs::is_directory(m_Destination, error))
  {
    throw UsageError("output " + m_Destination.string() + " is a directory");
  }
  if (!fs::is_directory(parent, error))
  {
    fs::create_directories(parent, error);
    if (error)
    {
      throw UsageError("cannot create " + parent.string() + ": " + error.message());
    }
  }
  RemoveStaleStagings(parent, name.string());
  m_Path = parent / ("." + name.string() + ".partial-" + std::to_string(getpid()));
  fs::remove_all(m_Path, error);
  m_Slot = RegisterStaging(m_Path);
  if (!fs::create_directory(m_Path, error))
  {
    UnregisterStaging(m_Slot);
    throw UsageError("cannot write in " + parent.string() + ": " +
                     (error ? error.message() : std::string("cannot create a folder")));
  }
}

OutputStaging::~OutputStaging()
{
  if (!m_Committed)
  {
    std::error_code ignored;
    fs::remove_all(m_Path, ignored);
  }
  UnregisterStaging(m_Slot);
}

fs::path
OutputStaging::FilePath() const
{
  return m_Path / m_Destination.filename();
}

void
OutputStaging::RequireSpace(std::uintmax_t bytes) const
{
  struct statvfs info
  {};
  if (statvfs(m_Path.c_str(), &info) != 0)
  {
    return;
  }
  const std::uintmax_t available = static_cast<std::uintmax_t>(info.f_bavail) * info.f_frsize;
  if (available < bytes)
  {
    throw UsageError("not enough disk space for " + m_Destination.string() + ": the results need about " +
                     DescribeBytes(bytes) + ", " + DescribeBytes(available) + " free");
  }
}

void
OutputStaging::Commit(Existing existing)
{
  std::error_code error;
  if (m_Kind == Kind::File)
  {
    fs::rename(FilePath(), m_Destination, error);
    if (error)
    {
      throw UsageError("cannot write " + m_Destination.string() + ": " + error.message());
    }
    fs::remove_all(m_Path, error);
  }
  else if (existing == Existing::Replace && fs::exists(m_Destination))
  {
    const fs::path old = m_Path.parent_path() / (m_Path.filename().string() + "-old");
    fs::rename(m_Destination, old, error);
    if (!error)
    {
      fs::rename(m_Path, m_Destination, error);
    }
    if (error)
    {
      throw UsageError("cannot replace " + m_Destination.string() + ": " + error.message());
    }
    fs::remove_all(old, error);
  }
  else if (!fs::exists(m_Destination) || (fs::is_directory(m_Destination) && fs::is_empty(m_Destination)))
  {
    fs::remove(m_Destination, error);
    fs::rename(m_Path, m_Destination, error);
    if (error)
    {
      throw UsageError("cannot write " + m_Destination.string() + ": " + error.message());
    }
  }
  else
  {
    for (const auto & entry : fs::directory_iterator(m_Path))
    {
      const fs::path target = m_Destination / entry.path().filename();
      if (fs::is_directory(target) || fs::is_directory(entry.path()))
      {
        fs::remove_all(target); // rename replaces a file, not a folder
      }
      fs::rename(entry.path(), target);
    }
    fs::remove_all(m_Path, error);
  }
  m_Committed = true;
  UnregisterStaging(m_Slot);
  m_Slot = -1;
}

void
RequireMemory(std::uintmax_t bytes, const std::string & what)
{
  struct rlimit limit
  {};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
  {
    return;
  }
  // The address space in use now: the first field of /proc/self/statm, in pages.
  std::uintmax_t inUse = 0;
  std::ifstream  statm("/proc/self/statm");
  statm >> inUse;
  inUse *= static_cast<std::uintmax_t>(sysconf(_SC_PAGESIZE));
  const std::uintmax_t cap = static_cast<std::uintmax_t>(limit.rlim_cur);
  if (inUse + bytes > cap)
  {
    throw UsageError(what + " needs about " + DescribeBytes(bytes) + " of memory, but the address-space limit " +
                     "(ulimit -v) of " + DescribeBytes(cap) + " leaves " +
                     DescribeBytes(cap > inUse ? cap - inUse : 0));
  }
}
// An output folder written before with the other layout (one sheet's files, or a folder
// per sheet) loses those files, so that nothing stale is mistaken for this run's results.
void
RemoveOtherLayout(const std::filesystem::path &    output,
                  bool                             folderPerSheet,
                  const std::vector<std::string> & oneSheetFiles)
{
  std::error_code error;
  if (!std::filesystem::is_directory(output, error))
  {
    return;
  }
  for (const auto & entry : std::filesystem::directory_iterator(output, error))
  {
    const std::string name = entry.path().filename().string();
    const bool        sheetFolder = name.size() == 8 && name.rfind("sheet-", 0) == 0 &&
                             std::isdigit(static_cast<unsigned char>(name[6])) &&
                             std::isdigit(static_cast<unsigned char>(name[7])) && entry.is_directory();
    const bool oneSheetFile = std::find(oneSheetFiles.begin(), oneSheetFiles.end(), name) != oneSheetFiles.end();
    if ((folderPerSheet && oneSheetFile) || sheetFolder)
    {
      std::filesystem::remove_all(entry.path(), error);
    }
  }
}

} // namespace vu
