# Builds nbt's examples against the installed library; make install puts this
# file in PREFIX/share/nbt/examples as Makefile (GNU make). From any writable
# directory:
#
#   make -f PREFIX/share/nbt/examples/Makefile           plan_example, airlight_example,
#                                                         and demo_fog where nbt-gl is installed
#   make -f PREFIX/share/nbt/examples/Makefile demo_fog  one of them
#
# pkg-config must find nbt.pc (and nbt-gl.pc): for a prefix it does not search,
# set PKG_CONFIG_PATH=PREFIX/lib/pkgconfig in the environment, and run the
# programs with LD_LIBRARY_PATH=PREFIX/lib unless that is a system library
# directory. demo_fog also needs the EGL, OpenGL and libpng development files
# (Debian: libegl-dev libopengl-dev libpng-dev).
#
#   ./plan_example [DIR]     the planner from C: tables for a scene at a stated error
#   ./airlight_example       airlight by the Legendre series and by the direct integral
#   ./demo_fog [OUT.png]     a point light in fog drawn by nbt's shaders (EGL, no window)

PKG_CONFIG = pkg-config
CC = cc
CFLAGS = -O2 -g
# the directory of this Makefile: the sources beside it
EXAMPLES := $(dir $(lastword $(MAKEFILE_LIST)))
SELF := $(lastword $(MAKEFILE_LIST))

all: plan_example airlight_example
	@if $(PKG_CONFIG) --exists nbt-gl; then $(MAKE) -f $(SELF) demo_fog; \
	else echo "nbt-gl is not installed (nbt was built without GL): demo_fog is not built"; fi

plan_example: $(EXAMPLES)plan_example.c
	$(CC) $(CFLAGS) $(CPPFLAGS) $(EXAMPLES)plan_example.c `$(PKG_CONFIG) --cflags nbt` \
	  $(LDFLAGS) `$(PKG_CONFIG) --libs nbt` -lm -o $@

airlight_example: $(EXAMPLES)airlight_example.c
	$(CC) $(CFLAGS) $(CPPFLAGS) $(EXAMPLES)airlight_example.c `$(PKG_CONFIG) --cflags nbt` \
	  $(LDFLAGS) `$(PKG_CONFIG) --libs nbt` -lm -o $@

demo_fog: $(EXAMPLES)demo_fog.c $(EXAMPLES)egl_headless.c $(EXAMPLES)egl_headless.h $(EXAMPLES)font5x7.h
	$(CC) $(CFLAGS) $(CPPFLAGS) $(EXAMPLES)demo_fog.c $(EXAMPLES)egl_headless.c \
	  `$(PKG_CONFIG) --cflags nbt-gl egl opengl libpng` \
	  $(LDFLAGS) `$(PKG_CONFIG) --libs nbt-gl nbt egl opengl libpng` -lm -o $@

clean:
	rm -f plan_example airlight_example demo_fog

.PHONY: all clean
