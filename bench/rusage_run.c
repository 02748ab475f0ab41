/* Runs a command and reports what it cost, for bench/bench_process.py:

     build/rusage_run COMMAND [ARGS...]

   The command inherits stdin, stdout and stderr; when it has exited, one more
   line goes to stderr:

     rusage_run: status S wall W user U sys Y maxrss_kib M

   (seconds; S is the exit status, or 128 + the signal that ended it). Why not
   wait4 from Python: Linux keeps, across exec, the peak memory of the process
   that was forked, so a command started by Python reports Python's peak if
   that is larger. Forked from this small program, it reports its own. */
#define _GNU_SOURCE
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static double seconds(struct timeval t) { return (double)t.tv_sec + (double)t.tv_usec * 1e-6; }

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: rusage_run COMMAND [ARGS...]\n");
    return 2;
  }
  struct timespec start, end;
  clock_gettime(CLOCK_MONOTONIC, &start);
  const pid_t pid = fork();
  if (pid < 0) {
    fprintf(stderr, "rusage_run: fork: %s\n", strerror(errno));
    return 1;
  }
  if (pid == 0) {
    execvp(argv[1], argv + 1);
    fprintf(stderr, "rusage_run: %s: %s\n", argv[1], strerror(errno));
    _exit(127);
  }
  int status = 0;
  struct rusage usage;
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) {
      fprintf(stderr, "rusage_run: wait4: %s\n", strerror(errno));
      return 1;
    }
  }
  clock_gettime(CLOCK_MONOTONIC, &end);
  const double wall = (double)(end.tv_sec - start.tv_sec) + (double)(end.tv_nsec - start.tv_nsec) * 1e-9;
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  fprintf(stderr, "rusage_run: status %d wall %.6f user %.6f sys %.6f maxrss_kib %ld\n", code, wall,
          seconds(usage.ru_utime), seconds(usage.ru_stime), usage.ru_maxrss);
  return code;
}
