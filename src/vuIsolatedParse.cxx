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
#include "vuIsolatedParse.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace itk {
namespace detail {
namespace {
// Moves `bytes` through `fd` with read or write, resuming after interruptions and short
// transfers; false when the other end is gone.
template <typename Transfer, typename Pointer>
bool
TransferAll(Transfer transfer, int fd, Pointer data, size_t bytes)
{
  while (bytes > 0)
  {
    const ssize_t n = transfer(fd, data, bytes);
    if (n < 0 && errno == EINTR)
    {
      continue;
    }
    if (n <= 0)
    {
      return false;
    }
    data += n;
    bytes -= static_cast<size_t>(n);
  }
  return true;
}

bool
WriteAll(int fd, const void * data, size_t bytes)
{
  return TransferAll(write, fd, static_cast<const char *>(data), bytes);
}

bool
ReadAll(int fd, void * data, size_t bytes)
{
  return TransferAll(read, fd, static_cast<char *>(data), bytes);
}

void
LimitChild(const std::vector<std::string> & files)
{
  uintmax_t largest = 0;
  for (const std::string & f : files)
  {
    std::error_code error;
    const uintmax_t size = std::filesystem::file_size(f, error);
    largest = std::max<uintmax_t>(largest, error ? 0 : size);
  }
  uintmax_t     inUse = 0;
  std::ifstream statm("/proc/self/statm");
  statm >> inUse;
  inUse *= static_cast<uintmax_t>(sysconf(_SC_PAGESIZE));
  struct rlimit limit
  {};
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer reserves terabytes of address space for its shadow memory: its own
  // allocator limits what one allocation may take instead (allocator_may_return_null).
  const bool limitAddressSpace = false;
#else
  const bool   limitAddressSpace = true;
#endif
  if (limitAddressSpace && getrlimit(RLIMIT_AS, &limit) == 0)
  {
    const rlim_t wanted = static_cast<rlim_t>(inUse + 8 * largest + (uintmax_t{ 256 } << 20));
    if (limit.rlim_cur == RLIM_INFINITY || wanted < limit.rlim_cur)
    {
      limit.rlim_cur = wanted;
      setrlimit(RLIMIT_AS, &limit);
    }
  }
  // A core file of each aborting child would be written where the user runs the tool.
  struct rlimit noCore
  {};
  setrlimit(RLIMIT_CORE, &noCore);
  // The time limit is on the processor time the child uses, which the load of a shared
  // machine does not eat into (a wall-clock limit refused good files on a busy machine);
  // a wall-clock alarm at four times that ends a child that waits instead of working.
#if defined(__SANITIZE_ADDRESS__)
  // Instrumented code runs several times slower.
  const rlim_t slowdown = 8;
#else
  const rlim_t slowdown = 1;
#endif
  const rlim_t  seconds = slowdown * static_cast<rlim_t>(10 + files.size() / 20);
  struct rlimit cpu
  {};
  if (getrlimit(RLIMIT_CPU, &cpu) == 0 && (cpu.rlim_cur == RLIM_INFINITY || seconds < cpu.rlim_cur))
  {
    cpu.rlim_cur = seconds;
    setrlimit(RLIMIT_CPU, &cpu);
  }
  alarm(static_cast<unsigned>(4 * seconds));
}

std::string
DescribeDeath(int status)
{
  if (!WIFSIGNALED(status))
  {
    return "stopped";
  }
  switch (WTERMSIG(status))
  {
    case SIGABRT:
      return "aborted";
    case SIGALRM:
    case SIGXCPU:
      return "ran out of time";
    case SIGSEGV:
    case SIGBUS:
    case SIGFPE:
    case SIGILL:
      return "crashed";
    default:
      return strsignal(WTERMSIG(status));
  }
}
} // namespace

IsolatedParse
ParseInChildProcess(const std::vector<std::string> &                             files,
                    const std::function<std::string(const std::string & file)> & parse)
{
  IsolatedParse out;
  if (files.empty())
  {
    return out;
  }
  int channel[2];
  if (pipe(channel) != 0)
  {
    for (const std::string & f : files)
    {
      out.Results.push_back(parse(f));
    }
    return out;
  }
  const pid_t child = fork();
  if (child < 0)
  {
    close(channel[0]);
    close(channel[1]);
    for (const std::string & f : files)
    {
      out.Results.push_back(parse(f));
    }
    return out;
  }
  if (child == 0)
  {
    close(channel[0]);
    // The child dies by the default actions: a handler of the program (one that saves
    // state or removes its outputs) must not run in it.
    for (const int signal : { SIGABRT, SIGALRM, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGINT, SIGTERM, SIGHUP, SIGQUIT })
    {
      std::signal(signal, SIG_DFL);
    }
    // An assertion's message would reach the user's terminal: the parent reports instead.
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0)
    {
      dup2(null, STDERR_FILENO);
      close(null);
    }
    LimitChild(files);
    for (const std::string & f : files)
    {
      std::string result;
      try
      {
        result = parse(f);
      }
      catch (const std::bad_alloc &)
      {
        // Out of the child's memory: the file claims more than it can justify.
        _exit(3);
      }
      catch (...)
      {
        _exit(4);
      }
      const uint64_t bytes = result.size();
      if (!WriteAll(channel[1], &bytes, sizeof(bytes)) || !WriteAll(channel[1], result.data(), result.size()))
      {
        _exit(0);
      }
    }
    _exit(0);
  }
  close(channel[1]);
  uint64_t bytes = 0;
  while (out.Results.size() < files.size() && ReadAll(channel[0], &bytes, sizeof(bytes)))
  {
    std::string result(static_cast<size_t>(std::min<uint64_t>(bytes, uint64_t{ 1 } << 30)), '\0');
    if (!ReadAll(channel[0], result.data(), result.size()))
    {
      break;
    }
    out.Results.push_back(std::move(result));
  }
  close(channel[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR)
  {}
  if (out.Results.size() < files.size())
  {
    out.FailedFile = files[out.Results.size()];
    if (WIFEXITED(status))
    {
      out.Failure = WEXITSTATUS(status) == 3 ? "ran out of memory" : "failed";
    }
    else
    {
      out.Failure = DescribeDeath(status);
    }
  }
  return out;
}
} // namespace detail
} // namespace itk
