#!/usr/bin/env bash
# Measures the thin-glass approximation of excitation rays (docs/fluorescence.md):
#   A  : distant UVB light, direct excitation crossing glass straight with Fresnel weight
#   A' : an area light in the same direction, same approximation
#   B  : the same area light, `full` mode, excitation rays stopped by glass (exact:
#        light reaches the solution only through refracting continuation paths)
#   C  : the same, excitation rays solving for the refracted path through the planar walls
#        (`connect`, exact with `full`), at the fast spp
# Prints the mean fluorescence radiance of each and the relative differences.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${CHLOROVDB:-build/src/cli/chlorovdb}
spp_fast=${SPP_FAST:-64}
spp_exact=${SPP_EXACT:-1024}
out=${OUT:-out/glass_excitation}
mkdir -p "$out"

scene() {  # $1 light json, $2 mode, $3 glass policy
  cat <<JSON
{
  "length_unit": "cm",
  "render": {"resolution": [48, 48], "wavelengths": 8, "fluorescence": "$2", "excitation_through_glass": "$3",
             "max_depth": 64},
  "camera": {"type": "orthographic", "position": [0, 3, 20], "look_at": [0, 3, 0], "height": 6},
  "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
  "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                "glass_to_solution": {"type": "dielectric", "ior": 0.8913}},
  "media": {"solution": {"solvent": {"rayleigh": false},
                         "pigments": [{"pigment": "chl", "concentration": 5, "unit": "uM"}]}},
  "shapes": [
    {"type": "box", "min": [-2.2, 0, -2.2], "max": [2.2, 6.4, 2.2], "material": "glass"},
    {"type": "box", "min": [-2.0, 0.2, -2.0], "max": [2.0, 6.2, 2.0], "material": "glass_to_solution", "inside": "solution"}
    $1
  ]
  $4
}
JSON
}
# Irradiance E on a plane facing the light (E = 1e4 × the lamp table): distant light scale E; an area light of
# radiance L subtending solid angle Ω (square of side s at distance d: Ω ≈ s²/d²) gives E ≈ L Ω.
side=40; dist=60
omega=$(awk -v s=$side -v d=$dist 'BEGIN{print s*s/(d*d)}')
L=$(awk -v o="$omega" 'BEGIN{print 1e4/o}')
area=", {\"type\": \"quad\", \"corner\": [$dist, $(awk -v s=$side 'BEGIN{print 3-s/2}'), $(awk -v s=$side 'BEGIN{print s/2}')], \"edge_u\": [0, $side, 0], \"edge_v\": [0, 0, -$side], \"emission\": {\"spectrum\": \"UVB-TL12\", \"scale\": $L}}"
distant=", \"lights\": [{\"type\": \"distant\", \"direction\": [-1, 0, 0], \"spectrum\": \"UVB-TL12\", \"scale\": 1e4}]"

scene "" direct fresnel "$distant" > "$out/A.json"
scene "$area" direct fresnel "" > "$out/A_area.json"
scene "$area" full block "" > "$out/B.json"
scene "$area" full connect "" > "$out/C.json"
for s in A A_area C; do "$bin" render "$out/$s.json" -o "$out/$s.exr" --spp "$spp_fast" -q; done
"$bin" render "$out/B.json" -o "$out/B.exr" --spp "$spp_exact" -q
"$bin" render "$out/B.json" -o "$out/B_seed2.exr" --spp "$spp_exact" --seed 2 -q  # noise estimate
for s in A A_area B B_seed2 C; do
  printf '%s ' "$s"; oiiotool "$out/$s.exr" --ch fluorescence.R,fluorescence.G,fluorescence.B --printstats 2>/dev/null | grep "Stats Avg" | sed 's/.*Avg://'
done
