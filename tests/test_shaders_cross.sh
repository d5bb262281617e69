#!/bin/sh
# tests/test_shaders_cross.sh: the HLSL (shader model 5.0 and 6.0) and MSL
# that make generated from the Vulkan SPIR-V with SPIRV-Cross. Each HLSL file
# is compiled back with glslang's HLSL front end (glslangValidator -D) and,
# where installed, glslc -x hlsl; the resources keep the Vulkan bindings
# doc/shaders.md lists (cbuffer/texture registers, MSL [[buffer]]/[[texture]]
# indices); and the check can fail: a broken copy is rejected.
. "${top_srcdir:-.}/tests/testlib.sh"
D=${NBT_SHADERS_CROSS:-}
if [ -z "$D" ]; then
  echo "SKIP: HLSL/MSL not generated (configure found no spirv-cross, glslangValidator or EGL/OpenGL for libnbt-gl)"
  exit 77
fi
command -v glslangValidator >/dev/null 2>&1 || { echo "SKIP: glslangValidator not found (Debian: glslang-tools)"; exit 77; }
GLSLC=${NBT_GLSLC:-no}
[ "$GLSLC" = no ] && echo "note: glslc not found (Debian: glslc): HLSL checked with glslangValidator -D only"
n=0
for v in $NBT_SHADER_VARIANTS; do
  for sm in sm5 sm6; do
    f=$D/hlsl/$sm/nbt_$v.hlsl
    [ -s "$f" ] && ok || bad "$f missing or empty"
    glslangValidator -D -V -S frag -e main -o "$tmp/$v.$sm.spv" "$f" >"$tmp/log" 2>&1 && ok ||
      bad "glslangValidator -D rejects $f: $(head -5 "$tmp/log")"
    if [ "$GLSLC" != no ]; then
      "$GLSLC" -x hlsl -fshader-stage=frag -o "$tmp/$v.$sm.glslc.spv" "$f" >"$tmp/log" 2>&1 && ok ||
        bad "glslc -x hlsl rejects $f: $(head -5 "$tmp/log")"
    fi
    n=$((n + 1))
  done
  m=$D/msl/nbt_$v.metal
  grep -q "fragment main0_out main0(" "$m" 2>/dev/null && ok || bad "$m has no fragment entry point"
done
[ "$n" -ge 12 ] && ok || bad "only $n HLSL files checked"

# the bindings doc/shaders.md gives: uniform blocks b0-b2, b15, tables t3.., the same indices in MSL
has() { grep -q -- "$2" "$1" && ok || bad "$1 lacks '$2'"; }
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "cbuffer nbt_weights_block : register(b0)"
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "cbuffer nbt_H_block : register(b1)"
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "Texture2D<float4> nbt_H0 : register(t3)"
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "Texture2D<float4> nbt_H3 : register(t6)"
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "SamplerState sampler_nbt_H3 : register(s6)"
has "$D/hlsl/sm5/nbt_surface_legendre.hlsl" "cbuffer nbt_J_block : register(b2)"
has "$D/hlsl/sm5/nbt_surface_legendre.hlsl" "Texture2D<float4> nbt_J1_0 : register(t7)"
has "$D/hlsl/sm5/nbt_surface_legendre.hlsl" "Texture2D<float4> nbt_Jn_3 : register(t14)"
has "$D/hlsl/sm5/nbt_airlight_gsliced.hlsl" "Texture3D<float4> nbt_H0 : register(t3)"
has "$D/hlsl/sm5/nbt_beam_fit.hlsl" "cbuffer nbt_beam_fit_block : register(b15)"
has "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" "float4 nbt_hw\[4\] : packoffset(c0)"
has "$D/hlsl/sm6/nbt_airlight_gsliced.hlsl" "float nbt_g : packoffset(c1)"
grep -l '_[0-9][0-9]*_nbt_' "$D"/hlsl/sm*/*.hlsl >"$tmp/ids" 2>/dev/null; [ ! -s "$tmp/ids" ] && ok ||
  bad "cbuffer members still carry SPIR-V ids in $(cat "$tmp/ids")"
has "$D/msl/nbt_airlight_legendre.metal" "nbt_H0 \[\[texture(3)\]\]"
has "$D/msl/nbt_beam_fit.metal" "\[\[buffer(15)\]\]"

# the validator can say no: the same file with the weights or a table left undeclared
# (a missing entry point is only a warning to glslang: the weights' declaration goes instead)
grep -v 'float4 nbt_hw\[' "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" >"$tmp/now.hlsl"
glslangValidator -D -V -S frag -e main -o "$tmp/x.spv" "$tmp/now.hlsl" >/dev/null 2>&1 &&
  bad "glslangValidator -D accepts HLSL without the weights' declaration" || ok
grep -v 'nbt_H0 : register' "$D/hlsl/sm5/nbt_airlight_legendre.hlsl" >"$tmp/notex.hlsl"
glslangValidator -D -V -S frag -e main -o "$tmp/x.spv" "$tmp/notex.hlsl" >/dev/null 2>&1 &&
  bad "glslangValidator -D accepts HLSL with an undeclared texture" || ok
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
