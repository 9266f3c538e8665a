// stepcount: how many instructions, and how many taken branches, one thread of a program runs
// between two getpid() system calls (the marks), counted exactly by single-stepping it with
// ptrace. For machines whose hardware counters are not available (`perf stat` says "not
// supported", as in the virtual machines raylab is developed on); see PERFORMANCE.md, "How to
// measure" (a busy minute). Used by scripts/count-instructions.sh, which builds it with `cc -O2`.
//
//   stepcount HISTOGRAM PROGRAM [ARGS...]
//
// The thread that makes the first getpid call is single-stepped until it makes the next one;
// every other thread runs on to its own system calls. A step whose next instruction is not
// within 15 bytes after it counts as a taken branch (a short forward jump is missed, which
// compilers rarely emit in hot loops); a `rep` string instruction's iterations (same address)
// are counted apart. HISTOGRAM gets the executable's load address ("base HEX"), then one line
// per address: "ADDRESS TAKEN_FROM_HERE EXECUTED", for scripts/stepcount-report.py.
//
// About 20 µs a step in a virtual machine: a 512 × 32 lab pass (6 million instructions) takes
// two to three minutes.
#define _GNU_SOURCE
#include <errno.h>
#include <libgen.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ptrace.h>
#include <sys/syscall.h>
#include <sys/user.h>
#include <sys/wait.h>
#include <unistd.h>

#define TABLE_BITS 22
#define TABLE_SIZE (1u << TABLE_BITS)
static unsigned long long keys[TABLE_SIZE], taken_from[TABLE_SIZE], executed[TABLE_SIZE];

// The slot of `address` in the open-addressing table.
static size_t slot(unsigned long long address) {
    size_t h = (size_t)((address * 0x9E3779B97F4A7C15ull) >> (64 - TABLE_BITS));
    while (keys[h] && keys[h] != address) h = (h + 1) & (TABLE_SIZE - 1);
    keys[h] = address;
    return h;
}

// The start of the executable's first mapping (file offset 0): its load address.
static unsigned long long load_address(pid_t thread, const char *program) {
    char path[64], line[1024];
    snprintf(path, sizeof path, "/proc/%d/maps", thread);
    FILE *maps = fopen(path, "r");
    unsigned long long base = 0;
    while (maps && fgets(line, sizeof line, maps)) {
        unsigned long long start, end, offset;
        char perms[8];
        if (sscanf(line, "%llx-%llx %7s %llx", &start, &end, perms, &offset) == 4 && offset == 0 &&
            strstr(line, program)) {
            base = start;
            break;
        }
    }
    if (maps) fclose(maps);
    return base;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: stepcount HISTOGRAM PROGRAM [ARGS...]\n");
        return 2;
    }
    char *name = strdup(argv[2]);
    const char *program = basename(name);
    pid_t child = fork();
    if (child == 0) {
        ptrace(PTRACE_TRACEME, 0, 0, 0);
        raise(SIGSTOP);
        execv(argv[2], argv + 2);
        perror("stepcount: exec");
        _exit(127);
    }
    int status;
    waitpid(child, &status, 0);
    ptrace(PTRACE_SETOPTIONS, child, 0,
           PTRACE_O_TRACECLONE | PTRACE_O_EXITKILL | PTRACE_O_TRACESYSGOOD);
    ptrace(PTRACE_SYSCALL, child, 0, 0);

    pid_t stepping = 0;  // the marked thread; -1 once its second mark is reached
    unsigned long long instructions = 0, taken = 0, rep_iterations = 0, last = 0, base = 0;
    for (;;) {
        pid_t thread = waitpid(-1, &status, __WALL);
        if (thread < 0) break;
        if (WIFEXITED(status) || WIFSIGNALED(status)) continue;
        int signal = WSTOPSIG(status), pass_on = 0;
        struct user_regs_struct regs;
        if (signal == (SIGTRAP | 0x80)) {
            // A system call's entry or exit: the first getpid entry starts the count.
            ptrace(PTRACE_GETREGS, thread, 0, &regs);
            if (stepping == 0 && (long)regs.orig_rax == SYS_getpid &&
                regs.rax == (unsigned long long)-ENOSYS) {
                stepping = thread;
                base = load_address(thread, program);
            }
        } else if (signal == SIGTRAP && thread == stepping && (status >> 16) == 0) {
            ptrace(PTRACE_GETREGS, thread, 0, &regs);
            unsigned long long rip = regs.rip;
            long word = ptrace(PTRACE_PEEKTEXT, thread, (void *)rip, 0);
            if ((word & 0xffff) == 0x050f && (long)regs.rax == SYS_getpid) {
                // `syscall` about to make the second mark.
                stepping = -1;
                ptrace(PTRACE_SYSCALL, thread, 0, 0);
                continue;
            }
            if (rip == last) {
                rep_iterations++;
            } else {
                instructions++;
                executed[slot(rip)]++;
                if (last && !(rip > last && rip <= last + 15)) {
                    taken++;
                    taken_from[slot(last)]++;
                }
                last = rip;
            }
        } else if (signal != SIGTRAP && signal != SIGSTOP) {
            pass_on = signal;
        }
        if (thread == stepping)
            ptrace(PTRACE_SINGLESTEP, thread, 0, pass_on);
        else
            ptrace(PTRACE_SYSCALL, thread, 0, pass_on);
    }
    if (stepping != -1) {
        fprintf(stderr, "stepcount: the program did not make two getpid calls\n");
        return 1;
    }
    printf("%llu instructions, %llu taken branches (%.2f %%), %llu rep iterations\n", instructions,
           taken, 100.0 * taken / (instructions ? instructions : 1), rep_iterations);
    FILE *out = fopen(argv[1], "w");
    if (!out) {
        perror("stepcount: histogram");
        return 1;
    }
    fprintf(out, "base %llx\n", base);
    for (size_t h = 0; h < TABLE_SIZE; h++)
        if (keys[h]) fprintf(out, "%llx %llu %llu\n", keys[h], taken_from[h], executed[h]);
    fclose(out);
    return 0;
}
