#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Side-by-side PNG of evaluation renders: one row per case, the reference then the chosen
method's image, each enlarged and labelled (docs/evaluation.md's "misses" figures).

    python3 montage.py OUT.png DIR CASE:IMAGE:LABEL [CASE:IMAGE:LABEL ...]

DIR is a `lucent-cli evaluate` output folder (it holds CASE_ref_*.png and CASE_IMAGE.png, e.g.
IMAGE = sslpv-paper_q2); LABEL is printed under the method's image. Needs python3-pil.
"""
import glob
import os
import sys

from PIL import Image, ImageDraw

SCALE = 3
LABEL_HEIGHT = 14


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    out, folder, items = argv[1], argv[2], argv[3:]
    rows = []
    for item in items:
        case, image, label = item.split(":", 2)
        refs = glob.glob(os.path.join(folder, case + "_ref_*.png"))
        if len(refs) != 1:
            sys.exit(f"montage: expected one reference PNG for {case} in {folder}, found {len(refs)}")
        rows.append((case, Image.open(refs[0]).convert("RGB"),
                     Image.open(os.path.join(folder, f"{case}_{image}.png")).convert("RGB"),
                     f"{image}: {label}"))
    w = max(r[1].width for r in rows) * SCALE
    h = max(r[1].height for r in rows) * SCALE
    sheet = Image.new("RGB", (2 * w + 3, len(rows) * (h + 2 * LABEL_HEIGHT)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (case, ref, test, label) in enumerate(rows):
        y = i * (h + 2 * LABEL_HEIGHT)
        draw.text((2, y + 1), case, fill="black")
        for j, (img, text) in enumerate(((ref, "reference"), (test, label))):
            x = j * (w + 3)
            sheet.paste(img.resize((w, h), Image.NEAREST), (x, y + LABEL_HEIGHT))
            draw.text((x + 2, y + LABEL_HEIGHT + h + 1), text, fill="black")
    sheet.save(out)


if __name__ == "__main__":
    main(sys.argv)
