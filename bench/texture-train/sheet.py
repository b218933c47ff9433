"""Contact sheet: K images per model from a generated directory."""
import csv, sys, os
from PIL import Image, ImageDraw
d = sys.argv[1]; K = int(sys.argv[2]) if len(sys.argv) > 2 else 6
out = sys.argv[3] if len(sys.argv) > 3 else os.path.join(os.path.dirname(__file__) or '.', 'sheet.png')
models = [m.strip() for m in sys.argv[4].split('|')] if len(sys.argv) > 4 else None
rows = list(csv.DictReader(open(os.path.join(d, 'labels.csv'))))
by = {}
for r in rows:
    by.setdefault(r['model'], []).append(r['file'])
ms = models or list(by)
T = 128; lab = 150
W = lab + K * (T + 2); H = len(ms) * (T + 2)
sheet = Image.new('L', (W, H), 255); dr = ImageDraw.Draw(sheet)
for i, m in enumerate(ms):
    y = i * (T + 2)
    words = m.split(); line = ''; yy = y + 4
    for w in words:
        if len(line) + len(w) > 20:
            dr.text((2, yy), line, fill=0); yy += 12; line = ''
        line += w + ' '
    dr.text((2, yy), line, fill=0)
    for j, f in enumerate(sorted(by.get(m, []))[:K]):
        im = Image.open(os.path.join(d, f)).resize((T, T))
        sheet.paste(im, (lab + j * (T + 2), y))
sheet.save(out)
print(out, sheet.size)
