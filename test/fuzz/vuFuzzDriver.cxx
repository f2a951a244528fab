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
// A bounded random-mutation driver for the fuzz targets where libFuzzer is not used (a
// compiler other than Clang): runs every file of the corpus folders once, then mutations
// of them (bit flips, byte changes, interesting numbers and words, insertions, deletions,
// duplicated and spliced chunks) until -runs or -max_total_time is reached. Same
// command line shape as libFuzzer: FOLDER... [-runs=N] [-max_total_time=S] [-seed=S]
// (without -seed, a seed drawn at start, printed so that a run can be repeated),
// [-timeout=S] (per input, default 25) and [-artifact_prefix=P]: an input that crashes,
// aborts or runs longer than the timeout is written to P + "crash" or P + "timeout"
// before the process ends by the signal, as libFuzzer does.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <csignal>
#include <fcntl.h>
#include <unistd.h>

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size);

namespace {
using Bytes = std::vector<uint8_t>;

// The input being run, for the signal handlers (which may only use system calls).
const uint8_t * volatile g_Input = nullptr;
volatile size_t g_InputSize = 0;
char            g_CrashPath[4096];
char            g_TimeoutPath[4096];

void
SaveInputAndDie(int signal)
{
  const char * path = signal == SIGALRM ? g_TimeoutPath : g_CrashPath;
  const int    file = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (file >= 0)
  {
    size_t written = 0;
    while (written < g_InputSize)
    {
      const ssize_t n = write(file, g_Input + written, g_InputSize - written);
      if (n <= 0)
      {
        break;
      }
      written += static_cast<size_t>(n);
    }
    close(file);
  }
  const char message[] = "vuFuzzDriver: input saved (crash or timeout)\n";
  (void)!write(STDERR_FILENO, message, sizeof(message) - 1);
  std::signal(signal == SIGALRM ? SIGABRT : signal, SIG_DFL);
  std::raise(signal == SIGALRM ? SIGABRT : signal);
}

int
Run(const Bytes & input, unsigned timeout)
{
  g_Input = input.data();
  g_InputSize = input.size();
  alarm(timeout);
  LLVMFuzzerTestOneInput(input.data(), input.size());
  alarm(0);
  return 1;
}

const char * const Words[] = { "0",  "-1", "1e308", "nan",        "inf", "-0", "4294967296", "18446744073709551615",
                               "\n", " ",  "\\",    "9999999999", "1,",  ",",  "auto",       "%s" };

void
Mutate(Bytes & input, const std::vector<Bytes> & corpus, std::mt19937_64 & random)
{
  auto      pick = [&random](size_t n) { return n == 0 ? size_t(0) : static_cast<size_t>(random() % n); };
  const int count = 1 + static_cast<int>(random() % 4);
  for (int m = 0; m < count; ++m)
  {
    switch (random() % 8)
    {
      case 0: // flip a bit
        if (!input.empty())
        {
          input[pick(input.size())] ^= static_cast<uint8_t>(1u << (random() % 8));
        }
        break;
      case 1: // set a byte
        if (!input.empty())
        {
          const uint8_t special[] = { 0, 0xff, 0x7f, 0x80, '\n', ' ', '-', '9' };
          input[pick(input.size())] = random() % 2 ? special[random() % 8] : static_cast<uint8_t>(random());
        }
        break;
      case 2: // insert an interesting word
      {
        const char * word = Words[random() % (sizeof(Words) / sizeof(Words[0]))];
        input.insert(input.begin() + static_cast<long>(pick(input.size() + 1)), word, word + std::strlen(word));
        break;
      }
      case 3: // delete a chunk
        if (!input.empty())
        {
          const size_t at = pick(input.size());
          const size_t n = 1 + pick(std::min<size_t>(64, input.size() - at));
          input.erase(input.begin() + static_cast<long>(at), input.begin() + static_cast<long>(at + n));
        }
        break;
      case 4: // duplicate a chunk
        if (!input.empty())
        {
          const size_t at = pick(input.size());
          const size_t n = 1 + pick(std::min<size_t>(64, input.size() - at));
          const Bytes  chunk(input.begin() + static_cast<long>(at), input.begin() + static_cast<long>(at + n));
          input.insert(input.begin() + static_cast<long>(pick(input.size() + 1)), chunk.begin(), chunk.end());
        }
        break;
      case 5: // splice in a chunk of another input
      {
        const Bytes & other = corpus[pick(corpus.size())];
        if (!other.empty())
        {
          const size_t at = pick(other.size());
          const size_t n = 1 + pick(std::min<size_t>(256, other.size() - at));
          input.insert(input.begin() + static_cast<long>(pick(input.size() + 1)),
                       other.begin() + static_cast<long>(at),
                       other.begin() + static_cast<long>(at + n));
        }
        break;
      }
      case 6: // overwrite with a little- or big-endian extreme integer
        if (input.size() >= 4)
        {
          const uint32_t values[] = { 0u, 0xffffffffu, 0x7fffffffu, 0x80000000u, 0x10000u, 0xffffu };
          const uint32_t v = values[random() % 6];
          const size_t   at = pick(input.size() - 3);
          std::memcpy(&input[at], &v, 4);
        }
        break;
      default: // truncate
        if (!input.empty())
        {
          input.resize(pick(input.size()));
        }
        break;
    }
  }
}
} // namespace

int
main(int argc, char * argv[])
{
  long                     runs = 10000;
  double                   seconds = 60.0;
  unsigned long            seed = std::random_device{}();
  unsigned                 timeout = 25;
  std::string              prefix = "./";
  std::vector<std::string> folders;
  for (int i = 1; i < argc; ++i)
  {
    const std::string argument = argv[i];
    if (argument.rfind("-runs=", 0) == 0)
    {
      runs = std::atol(argument.c_str() + 6);
    }
    else if (argument.rfind("-max_total_time=", 0) == 0)
    {
      seconds = std::atof(argument.c_str() + 16);
    }
    else if (argument.rfind("-seed=", 0) == 0)
    {
      seed = std::strtoul(argument.c_str() + 6, nullptr, 10);
    }
    else if (argument.rfind("-timeout=", 0) == 0)
    {
      timeout = static_cast<unsigned>(std::atoi(argument.c_str() + 9));
    }
    else if (argument.rfind("-artifact_prefix=", 0) == 0)
    {
      prefix = argument.substr(17);
    }
    else if (argument.rfind("-", 0) == 0)
    {
      // libFuzzer options this driver does not have are accepted and ignored.
    }
    else
    {
      folders.push_back(argument);
    }
  }
  if (const char * override = std::getenv("VU_FUZZ_RUNS_OVERRIDE"))
  {
    runs = std::atol(override); // a test that may run no more than this (the seeds)
  }
  std::vector<Bytes> corpus;
  for (const std::string & folder : folders)
  {
    for (const auto & entry : std::filesystem::directory_iterator(folder))
    {
      std::ifstream in(entry.path(), std::ios::binary);
      corpus.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
  if (corpus.empty())
  {
    corpus.emplace_back();
  }
  std::snprintf(g_CrashPath, sizeof(g_CrashPath), "%scrash", prefix.c_str());
  std::snprintf(g_TimeoutPath, sizeof(g_TimeoutPath), "%stimeout", prefix.c_str());
  for (int signal : { SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGALRM })
  {
    std::signal(signal, SaveInputAndDie);
  }
  const auto start = std::chrono::steady_clock::now();
  long       executed = 0;
  for (const Bytes & input : corpus)
  {
    executed += Run(input, timeout);
  }
  std::mt19937_64 random(seed);
  while (executed < runs && std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < seconds)
  {
    Bytes input = corpus[static_cast<size_t>(random() % corpus.size())];
    Mutate(input, corpus, random);
    if (input.size() > 1 << 20)
    {
      input.resize(1 << 20);
    }
    executed += Run(input, timeout);
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("Done %ld runs in %.0f second(s), seed %lu, %zu corpus input(s): 0 crashes\n",
              executed,
              elapsed,
              seed,
              corpus.size());
  return 0;
}
