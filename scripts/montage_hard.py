#!/usr/bin/env python3
"""Assembles the README's pictures of the hard-shadow techniques from real runs (needs Pillow):

    dbuffer compare bunny --out out/bunny            (and acute-corner, fig8c-complex)
    dbuffer render fig8c-complex --method extended-light-map --elm-pattern 1 --out out/elm-gobo
    dbuffer render fig8c-complex --method extended-light-map --elm-depth-bits 8 --out out/elm-8
    python3 scripts/montage_hard.py out

docs/hard-SCENE.png: each hard technique's image above its METHOD-hard-error.png (red: a false
shadow, blue: a missed one, against reference-hard); docs/elm-fig8c-complex.png: the extended
light map's patterns and its 8-bit distances."""

import sys

from PIL import Image, ImageDraw, ImageFont

FONT = ImageFont.truetype("assets/fonts/DejaVuSans.ttf", 14)
METHODS = ["shadow-volume", "planar", "hybrid", "extended-light-map", "hard"]


def grid(tiles, cols, size, out):
    rows = (len(tiles) + cols - 1) // cols
    img = Image.new("RGB", (cols * size, rows * (size + 20)), (30, 30, 30))
    draw = ImageDraw.Draw(img)
    for i, (path, label) in enumerate(tiles):
        tile = Image.open(path).convert("RGB").resize((size, size), Image.LANCZOS)
        x, y = (i % cols) * size, (i // cols) * (size + 20)
        img.paste(tile, (x, y + 20))
        draw.text((x + 5, y + 2), label, fill=(235, 235, 235), font=FONT)
    img.save(out, optimize=True)


def main(root):
    for scene in ["bunny", "acute-corner"]:
        tiles = [(f"{root}/{scene}/{m}.png", m) for m in METHODS]
        tiles += [(f"{root}/{scene}/{m}-hard-error.png", "errors") for m in METHODS]
        grid(tiles, 5, 200, f"docs/hard-{scene}.png")
    grid(
        [
            (f"{root}/fig8c-complex/extended-light-map.png", "spot (--elm-pattern 0)"),
            (f"{root}/elm-gobo/image.png", "projected texture (1)"),
            (f"{root}/elm-8/image.png", "8-bit distances"),
        ],
        3,
        256,
        "docs/elm-fig8c-complex.png",
    )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out")
