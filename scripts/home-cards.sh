#!/usr/bin/env bash
# The home view's card pictures, assets/home/<tool>.png: each tool's example
# made ahead of time by the native CLI (the same core and the same requests
# the panels send), so that the home view loads no wasm at all (www/app/home.js
# shows them as plain images). Run it when a change alters what one of these
# examples looks like, look at the pictures, and commit them:
#   bash scripts/home-cards.sh        (FILIGREE_BIN=path overrides target/debug/filigree)
# Every picture is stored losslessly in its smallest PNG form (palette, grey
# or RGB, whichever is smallest), except Tangle's, whose anti-aliased greys
# are rounded to 16 levels (invisible at card size, half the bytes).
# It also prints the Inspect card's facts and checks that www/app/home.js shows
# the same ones (they are static text there).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${FILIGREE_BIN:-target/debug/filigree}
if [ ! -x "$bin" ]; then
  echo "home-cards: $bin is missing (cargo build --bin filigree)" >&2
  exit 1
fi
if ! python3 -c 'import PIL' 2>/dev/null; then
  echo "home-cards: needs Python's Pillow (pip install pillow)" >&2
  exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=assets/home
mkdir -p "$out"

# Pixel: the fish case of the Pixel panel (assets/pixel/cases.json), its
# parameters turned into the CLI's flags.
mapfile -t pixel < <(python3 - <<'EOF'
import json
c = json.load(open('assets/pixel/cases.json'))['fish']
print('--source'); print('assets/pixel/' + c['source'])
print('--mask'); print('assets/pixel/' + c['mask'])
print('--sheet'); print('assets/pixel/' + c['sheet'])
print('--strokes'); print('assets/pixel/' + c['strokes'])
hexes = lambda cs: ','.join('#%02x%02x%02x' % tuple(x[:3]) for x in cs) or 'none'
flags = {
    'density': lambda v: ['--density', str(v)],
    'margins': lambda v: ['--margins', '%d,%d' % tuple(v)],
    'partial': lambda v: ['--partial'] if v else [],
    'positions': lambda v: ['--positions', v],
    'colour': lambda v: ['--colour', v],
    'hsv': lambda v: ['--hsv', '%g,%g,%g' % tuple(v)],
    'exclude': lambda v: ['--exclude', hexes(v)],
    'd_max': lambda v: ['--dmax', str(v)],
    'element_colour': lambda v: ['--element-colour', v],
    'annotation_scale': lambda v: ['--annotation-scale', str(v)],
    'default_direction': lambda v: ['--default-direction', v],
    'seed': lambda v: ['--seed', str(v)],
}
for k, v in c['params'].items():
    if k not in flags:
        raise SystemExit(f'home-cards: the fish case has a parameter the script does not map: {k}')
    for a in flags[k](v):
        print(a)
EOF
)
"$bin" pixel "${pixel[@]}" --out "$tmp/pixel.png"

# Fit: the honeycomb generator at its default values, as the Fit panel's list shows it.
"$bin" render --program assets/patterns/honeycomb.flg --params '{}' --size 240 --supersample 2 --out "$tmp/fit.png"

# Inspect: the fish sprite itself (the inspect thumbnail of a 128 px sprite is the sprite).
cp assets/pixel/fish.png "$tmp/inspect.png"
"$bin" inspect --json assets/pixel/fish.png > "$tmp/inspect.json"

# Tangle: the leaf grammar, at most 400 steps and 4000 shapes, its pen 1.5
# drawing units (0.6 px here, the overall tone of the live canvas preview
# the card used to draw), fitted into 312×232 and set on white
# paper 320×240 (a 4 px margin), as the card drew it. A first render tells
# the drawing's aspect; the second is made at the width that fits.
tangle=(--grammar assets/tangle/leaf.tangle --steps 400 --max-shapes 4000 --stroke-width 1.5)
"$bin" tangle "${tangle[@]}" --png-width 320 --out "$tmp/tangle-aspect.png" > /dev/null
width=$(python3 -c "
from PIL import Image
w, h = Image.open('$tmp/tangle-aspect.png').size
print(min(312, int(232 * w / h)))")
"$bin" tangle "${tangle[@]}" --png-width "$width" --out "$tmp/tangle-fit.png"

# Micro: the gyroid example scene, sphere-traced at 160×120.
"$bin" micro render --scene assets/micro/gyroid.json --size 160x120 --out "$tmp/micro.png"

# Texture: the regular textons, seed 1, 128², tiled 2×2 below (the models tile).
"$bin" texture render --model texton-regular --seed 1 --size 128 --out "$tmp/texture-tile.png"

python3 - "$tmp" "$out" <<'EOF'
import io, json, sys
from PIL import Image

tmp, out = sys.argv[1], sys.argv[2]

def tangle():
    src = Image.open(f'{tmp}/tangle-fit.png').convert('L')
    assert src.width <= 312 and src.height <= 240, src.size
    img = Image.new('L', (320, 240), 255)
    img.paste(src, ((320 - src.width) // 2, (240 - src.height) // 2))
    # 16 grey levels, evenly spaced: only the anti-aliasing is rounded.
    return img.point(lambda v: round(v / 17) * 17)

def texture():
    tile = Image.open(f'{tmp}/texture-tile.png')
    img = Image.new(tile.mode, (2 * tile.width, 2 * tile.height))
    for x in (0, tile.width):
        for y in (0, tile.height):
            img.paste(tile, (x, y))
    return img

def encodings(img):
    """PNG encodings of img that decode to the same RGBA pixels."""
    rgba = img.convert('RGBA')
    opaque = rgba.getextrema()[3][0] == 255
    yield {}, rgba
    if opaque:
        yield {}, rgba.convert('RGB')
        r, g, b, _ = rgba.split()
        if r.tobytes() == g.tobytes() == b.tobytes():
            yield {}, r
    colours = rgba.getcolors(256)
    if colours:
        index = {c: i for i, (_, c) in enumerate(sorted(colours, key=lambda nc: -nc[0]))}
        p = Image.new('P', rgba.size)
        px = rgba.tobytes()
        p.frombytes(bytes(index[tuple(px[i:i + 4])] for i in range(0, len(px), 4)))
        entries = sorted(index, key=index.get)
        p.putpalette([v for c in entries for v in c[:3]])
        if not opaque:
            p.info['transparency'] = bytes(c[3] for c in entries)
        for bits in (1, 2, 4, 8):
            if len(entries) <= 1 << bits:
                yield {'bits': bits}, p

def smallest(img):
    want = img.convert('RGBA').tobytes()
    best = None
    for opts, cand in encodings(img):
        buf = io.BytesIO()
        extra = {'transparency': cand.info['transparency']} if 'transparency' in cand.info else {}
        cand.save(buf, 'PNG', optimize=True, **opts, **extra)
        data = buf.getvalue()
        if Image.open(io.BytesIO(data)).convert('RGBA').tobytes() != want:
            continue
        if best is None or len(data) < len(best):
            best = data
    return best

pictures = {
    'pixel': Image.open(f'{tmp}/pixel.png'),
    'fit': Image.open(f'{tmp}/fit.png'),
    'inspect': Image.open(f'{tmp}/inspect.png'),
    'tangle': tangle(),
    'micro': Image.open(f'{tmp}/micro.png'),
    'texture': texture(),
}
for tool, img in pictures.items():
    data = smallest(img)
    with open(f'{out}/{tool}.png', 'wb') as f:
        f.write(data)
    note = '' if len(data) < 40_000 else '  (over the 40 KB budget)'
    print(f'{out}/{tool}.png: {img.width}×{img.height}, {len(data):,} bytes{note}')

# The Inspect card's text: size, colour count and the first 8 clusters.
r = json.load(open(f'{tmp}/inspect.json'))
facts = f"{r['width']}×{r['height']} px · {r['colour_count']} colours"
swatches = ['#%02x%02x%02x' % tuple(c['rgba'][:3]) for c in r['clusters'][:8]]
print(f'inspect card: {facts}; swatches {" ".join(swatches)}')
home = open('www/app/home.js', encoding='utf-8').read()
missing = [s for s in [facts, *swatches] if f"'{s}'" not in home]
if missing:
    sys.exit(f'home-cards: www/app/home.js does not show {", ".join(missing)}: update its Inspect card')
EOF
