# Sourced by the benchmark scripts (from the repository's top directory): the hsr binary they
# time — HSR, default build/hsr, built by scripts/build.sh when missing — python3 for their
# tables, and bench_header, the lines that name a run (date, commit, processor).
hsr="${HSR:-build/hsr}"
[ -x "$hsr" ] || scripts/build.sh >/dev/null
command -v python3 >/dev/null || scripts/install-deps.sh python3

bench_header() {
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "cpu: $(grep -m1 "model name" /proc/cpuinfo | cut -d: -f2- | sed "s/^ //"), $(nproc) cores"
}
