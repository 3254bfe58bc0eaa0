# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: how the sanitizers report.
# halt_on_error / -fno-sanitize-recover: the first report ends the process with an error.
# detect_leaks: LeakSanitizer at exit, with the one suppression that lsan.supp explains.
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
# Two or more processes under mpirun (tests/mpi/): no leak check. OpenMPI's runtime (PMIx)
# allocates 32 bytes per process in its progress thread (libevent's event loop) inside
# components MPI_Finalize unloads, and keeps them to the end: a report whose frames are all in
# unloaded modules, which no suppression can name (the slow unwinder reaches libevent's frame,
# but made the G1 tests take over 15 minutes). knotwork's distributed code is leak-checked on
# one rank (the same tests' 1-rank runs, `--solver petsc` without mpirun); ASan and UBSan stay
# on for every rank.
export KNOTWORK_MPI_ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0"
# The Python module is a shared object loaded by an uninstrumented interpreter: the tests of it
# preload clang's shared ASan runtime (tests/CMakeLists.txt), and Python's own allocations,
# which it frees only at exit or never, are not knotwork's to judge: no leak check there.
