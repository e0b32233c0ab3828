#!/bin/sh
# in-debian13.sh ROOT COMMAND...: run COMMAND in the Debian 13 root ROOT (made by `make debian13-root`),
# from the current folder, as root. The mounts live in a mount namespace of their own, so they go
# when COMMAND ends and the host never sees them: /proc, /dev and /sys; the host's /tmp (xvfb-run
# -a then sees the host's displays and takes a free one); the folder holding the checkout, at the
# same path (the add-on, the test scripts, the artefacts and ../shared/meshes); and, when ../shared
# is a link to a folder outside it, that folder, at its own path, so that the link leads there.
set -eu
root=$(realpath "$1")
shift
parent=$(dirname "$(realpath "$(dirname "$0")/../..")")
shared=
if [ -d "$parent/shared" ]; then
	shared=$(realpath "$parent/shared")
	case "$shared" in "$parent"/*) shared= ;; esac
fi
exec unshare --mount --propagation private sh -eu -c '
	root=$1 parent=$2 here=$3 shared=$4
	shift 4
	mount -t proc proc "$root/proc"
	mount --rbind /dev "$root/dev"
	mount --rbind /sys "$root/sys"
	mount --bind /tmp "$root/tmp"
	# Shared first: should it contain the parent folder, the parent folder is mounted over it.
	if [ -n "$shared" ]; then
		mkdir -p "$root$shared"
		mount --bind "$shared" "$root$shared"
	fi
	mkdir -p "$root$parent"
	mount --bind "$parent" "$root$parent"
	exec chroot "$root" /usr/bin/env PATH=/usr/sbin:/usr/bin:/sbin:/bin sh -c "cd \"\$0\" && exec \"\$@\"" "$here" "$@"
' in-debian13 "$root" "$parent" "$(pwd)" "$shared" "$@"
