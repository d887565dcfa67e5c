#!/usr/bin/env bash
# Builds the trajdrift image with no registry: the statically linked binary is built on this machine
# (cargo with glibc's static libraries), then `podman build` puts it FROM scratch beside a static
# busybox as /bin/sh (the Kubernetes manifests' shell), and the image runs `trajdrift --version`.
#   deploy/container/build.sh            # image trajdrift:latest
#   IMAGE=registry.example/trajdrift:0.1.0 deploy/container/build.sh
# Needs: cargo, podman (apt-get install podman), a static busybox (apt-get install busybox-static).
set -euo pipefail
cd "$(dirname "$0")/../.."
IMAGE="${IMAGE:-trajdrift:latest}"
BUSYBOX="${BUSYBOX:-/bin/busybox}"

target="$(rustc -vV | sed -n 's/^host: //p')"
echo "== static trajdrift for $target"
# --target: crt-static applies to the binary only, not to build scripts and proc-macros.
RUSTFLAGS="-C target-feature=+crt-static" \
  nice -n 10 cargo build --release --locked --bin trajdrift --target "$target"
bin="target/$target/release/trajdrift"

static() { # a binary that needs no loader and no shared library
  ! readelf -l "$1" 2>/dev/null | grep -q "INTERP" && ! readelf -d "$1" 2>/dev/null | grep -q "NEEDED"
}
static "$bin" || { echo "error: $bin is linked dynamically; check RUSTFLAGS" >&2; exit 1; }
if ! static "$BUSYBOX"; then
  echo "error: $BUSYBOX is not a static busybox; apt-get install busybox-static, or set BUSYBOX" >&2
  exit 1
fi

ctx="$(mktemp -d)"
trap 'rm -rf "$ctx"' EXIT
cp "$bin" "$ctx/trajdrift"
strip "$ctx/trajdrift"
cp "$BUSYBOX" "$ctx/sh"
cat > "$ctx/Containerfile" <<'CONTAINERFILE'
FROM scratch
COPY trajdrift /usr/local/bin/trajdrift
COPY sh /bin/sh
ENV PATH=/usr/local/bin:/bin
CMD ["trajdrift", "--help"]
CONTAINERFILE
echo "== podman build $IMAGE (FROM scratch: no registry)"
podman build -t "$IMAGE" "$ctx"
podman image ls "$IMAGE"
echo "== trajdrift --version in the image"
# Some sandboxes refuse what podman's defaults ask of the kernel (crun on a hybrid cgroup tree; raising
# RLIMIT_NOFILE/NPROC): then run with runc and lowered limits, or set PODMAN_RUN_FLAGS yourself.
run_flags=()
if [ -n "${PODMAN_RUN_FLAGS:-}" ]; then
  read -r -a run_flags <<< "$PODMAN_RUN_FLAGS"
elif ! podman run --rm "$IMAGE" trajdrift --version; then
  echo "note: podman run failed with its defaults; retrying with runc and limits of 1024 files and processes" >&2
  command -v runc >/dev/null && run_flags+=(--runtime runc)
  run_flags+=(--ulimit nofile=1024:1024 --ulimit nproc=1024:1024)
fi
podman_run() { # global flags (--runtime) go before `run`
  local global=() local_flags=() i=0
  while [ $i -lt ${#run_flags[@]} ]; do
    if [ "${run_flags[$i]}" = "--runtime" ]; then global+=(--runtime "${run_flags[$((i + 1))]}"); i=$((i + 2))
    else local_flags+=("${run_flags[$i]}"); i=$((i + 1)); fi
  done
  podman "${global[@]}" run --rm "${local_flags[@]}" "$IMAGE" "$@"
}
podman_run trajdrift --version
# The manifests' form: a shell maps trajdrift's exit codes.
podman_run /bin/sh -c 'trajdrift topics /nonexistent.mcap; echo "exit code $?"'
