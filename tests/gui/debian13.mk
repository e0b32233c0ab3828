# Debian 13's Blender (4.3.2, embedding Debian's Python 3.13) in a Debian 13 root made by Debian's
# mmdebstrap from Debian's mirror: the GUI tests run there in a window under Xvfb, as in 3.4.1.
# The root is kept between runs and made again only when missing or when its recipe changes (the
# recipe is kept in $(DEBIAN13)/recipe). x11-apps and imagemagick grab the Xvfb screen
# (xwd, convert): Blender 4.3's own screenshot is black under Xvfb. mmdebstrap installs no Recommends.
space             := $(subst ,, )
comma             := ,
DEBIAN13          ?= .debian13
DEBIAN13_ROOT     := $(DEBIAN13)/root
DEBIAN13_MIRROR   := http://deb.debian.org/debian
DEBIAN13_PACKAGES := blender xvfb xauth python3-numpy x11-apps imagemagick
DEBIAN13_RECIPE   := mmdebstrap --mode=root --variant=minbase --include=$(subst $(space),$(comma),$(DEBIAN13_PACKAGES)) \
	trixie $(DEBIAN13_ROOT).new $(DEBIAN13_MIRROR)

# The host's package that makes the root. The Makefile adds it to PACKAGES, so every `make deps`
# installs it: a target-specific addition would be lost when deps was already made for another
# target of the same make.
DEBIAN13_HOST_PACKAGES := mmdebstrap
debian13-root: deps
	@test "$$(cat $(DEBIAN13)/recipe 2>/dev/null)" = "$(DEBIAN13_RECIPE)" || { \
		rm -rf $(DEBIAN13_ROOT) $(DEBIAN13_ROOT).new $(DEBIAN13)/recipe && mkdir -p $(DEBIAN13) \
		&& $(DEBIAN13_RECIPE) && mv $(DEBIAN13_ROOT).new $(DEBIAN13_ROOT) \
		&& echo "$(DEBIAN13_RECIPE)" > $(DEBIAN13)/recipe; }

.PHONY: debian13-root
