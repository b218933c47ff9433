# Seeded, stratified split of the designs into validation / test, made before
# any fit was run (python3 split.py prints the assignment; designs.json has it).
import random
KINDS = {
    "stripes": ["diagonal-stripes", "cross-hatch", "graph-paper-major", "tartan", "gp-chevrons"],
    "curves": ["seigaiha", "shippo", "gp-concentric-circles", "gp-sine-waves", "polka-dots"],
    "lattices": ["brick-wall", "honeycomb-outline", "gp-octogons", "gp-hexagons", "gp-triangles",
                 "gp-diamonds", "gp-squares", "gp-nested-squares", "gp-tessellation"],
}
N_VALIDATION = {"stripes": 2, "curves": 3, "lattices": 4}  # 9 of 19
rng = random.Random(1729)
split = {}
for kind, names in KINDS.items():
    names = sorted(names)
    rng.shuffle(names)
    for k, n in enumerate(names):
        split[n] = ("validation" if k < N_VALIDATION[kind] else "test", kind)
if __name__ == "__main__":
    for n in sorted(split):
        print(n, *split[n])
