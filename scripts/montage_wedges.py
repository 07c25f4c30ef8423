#!/usr/bin/env python3
"""Assembles the README's picture of penumbra wedges against the D-buffer from real runs (needs
Pillow):

    for s in fig1-large-light table1-224 acute-corner bunny; do
        dbuffer compare $s --out out/$s --size 512x512 --samples 1024
    done
    python3 scripts/montage_wedges.py out

docs/images/wedges-vs-dbuffer.png: one row per scene, reference | wedges | dbuffer | |ΔV| wedges |
|ΔV| dbuffer (compare's METHOD-error.png heatmaps, their legend strip once under the last row)."""

import sys

from PIL import Image, ImageDraw, ImageFont

FONT = ImageFont.truetype("assets/fonts/DejaVuSans.ttf", 13)
SCENES = ["fig1-large-light", "table1-224", "acute-corner", "bunny"]
COLUMNS = [
    ("reference.png", "reference"),
    ("wedges.png", "wedges"),
    ("dbuffer.png", "dbuffer"),
    ("wedges-error.png", "|ΔV| wedges"),
    ("dbuffer-error.png", "|ΔV| dbuffer"),
]
TILE, LABEL, HEADER = 200, 120, 16


def main(root):
    legend_h = 0
    legend = None
    sample = Image.open(f"{root}/{SCENES[0]}/wedges-error.png")
    if sample.height > sample.width:
        # The heatmap's legend strip under its square image.
        strip = sample.crop((0, sample.width, sample.width, sample.height))
        legend_h = round(strip.height * TILE / sample.width)
        legend = strip.resize((TILE, legend_h), Image.LANCZOS)
    width = LABEL + TILE * len(COLUMNS)
    height = HEADER + TILE * len(SCENES) + legend_h
    img = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    for c, (_, title) in enumerate(COLUMNS):
        draw.text((LABEL + c * TILE + 4, 1), title, fill=(0, 0, 0), font=FONT)
    for r, scene in enumerate(SCENES):
        y = HEADER + r * TILE
        draw.text((4, y + TILE // 2 - 8), scene, fill=(0, 0, 0), font=FONT)
        for c, (name, _) in enumerate(COLUMNS):
            tile = Image.open(f"{root}/{scene}/{name}").convert("RGB")
            tile = tile.crop((0, 0, tile.width, tile.width))
            img.paste(tile.resize((TILE, TILE), Image.LANCZOS), (LABEL + c * TILE, y))
    if legend is not None:
        y = HEADER + TILE * len(SCENES)
        for c in (3, 4):
            img.paste(legend, (LABEL + c * TILE, y))
    img.save("docs/images/wedges-vs-dbuffer.png", optimize=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out")
