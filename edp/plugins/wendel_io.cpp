// wendel_io: an increment's files written by a background thread while FreeFEM goes on (issue 20).
//
// Registered in the FreeFEM language (load "wendel_io"; lib/common.idp's writeArray, lib/io.idp's
// writeCellField and commitIncrement):
//
//   wendelSave(real[int] a, string path)   queue the file BinaryIO's SaveVec writes: the count as a
//                                          little-endian int64, then the values as float64 (same bytes)
//   wendelWrite(string path, string text)  queue a text file (the commit marker "done")
//   wendelFlush()                          wait until every queued file is written
//
// One writer thread takes the queue in order: a commit marker queued after an increment's files is written
// after them, so the driver, which takes an increment once its marker exists, never sees it half written.
// The values are copied when queued (the script may change the array at once). At exit (the end of the
// script or exit(n)) the queue is written out before the process ends; a process killed before that leaves
// its last increments without their marker, as a kill between two files did before. A file that cannot be
// written (a full disk) stops the process with exit code 3 and nothing more is written: no later marker.
#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <unistd.h>

namespace {

struct Job {
    std::string path;
    std::string bytes;
};

// on the heap and never destroyed: the writer thread may still wait on them while the process ends
std::mutex& mtx = *new std::mutex;
std::condition_variable& more = *new std::condition_variable;
std::condition_variable& idle = *new std::condition_variable;
std::deque<Job>& jobs = *new std::deque<Job>;
bool started = false, busy = false;

void writeOne(const Job& j)
{
    FILE* f = std::fopen(j.path.c_str(), "wb");
    bool ok = f != nullptr && std::fwrite(j.bytes.data(), 1, j.bytes.size(), f) == j.bytes.size();
    if (f != nullptr) ok = (std::fclose(f) == 0) && ok;
    if (!ok) {
        std::fprintf(stderr, "wendel_io: cannot write %s\n", j.path.c_str());
        std::fflush(stderr);
        _exit(3);           // no later file, no later commit marker
    }
}

void writer()
{
    std::unique_lock<std::mutex> lock(mtx);
    for (;;) {
        more.wait(lock, [] { return !jobs.empty(); });
        Job j = std::move(jobs.front());
        jobs.pop_front();
        busy = true;
        lock.unlock();
        writeOne(j);
        lock.lock();
        busy = false;
        if (jobs.empty()) idle.notify_all();
    }
}

void flushAll()
{
    std::unique_lock<std::mutex> lock(mtx);
    idle.wait(lock, [] { return jobs.empty() && !busy; });
}

void enqueue(std::string path, std::string bytes)
{
    std::lock_guard<std::mutex> lock(mtx);
    if (!started) {
        started = true;
        std::thread(writer).detach();
        std::atexit(flushAll);          // registered after FreeFEM's own: runs before them
    }
    jobs.push_back(Job{std::move(path), std::move(bytes)});
    more.notify_one();
}

long wendelSave(KN<double>* const& a, string* const& path)
{
    int64_t n = a->N();
    std::string bytes(sizeof(int64_t) + n * sizeof(double), '\0');
    std::memcpy(&bytes[0], &n, sizeof(int64_t));         // x86-64: little-endian, as BinaryIO's
    for (int64_t i = 0; i < n; ++i) {
        double v = (*a)[i];
        std::memcpy(&bytes[sizeof(int64_t) + i * sizeof(double)], &v, sizeof(double));
    }
    enqueue(*path, std::move(bytes));
    return 0;
}

long wendelWrite(string* const& path, string* const& text)
{
    enqueue(*path, *text);
    return 0;
}

long wendelFlush()
{
    flushAll();
    return 0;
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelSave", "(", new OneOperator2_<long, KN<double>*, string*>(wendelSave));
    Global.Add("wendelWrite", "(", new OneOperator2_<long, string*, string*>(wendelWrite));
    Global.Add("wendelFlush", "(", new OneOperator0<long>(wendelFlush));
}
LOADFUNC(Load_Init)
