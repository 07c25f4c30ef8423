#!/usr/bin/env python3
"""Puts images from real runs side by side, each under a caption, for the README (needs Pillow):

    python3 scripts/side_by_side.py OUT.png SIZE IMAGE=CAPTION [IMAGE=CAPTION ...]

Each image is scaled to SIZE pixels wide. The README's pictures made with it, and their runs:

docs/images/elm-fig8c-complex.png (the extended light map's patterns and its 8-bit distances):
    dbuffer render fig8c-complex --method extended-light-map --out out/elm-spot
    dbuffer render fig8c-complex --method extended-light-map --elm-pattern 1 --out out/elm-gobo
    dbuffer render fig8c-complex --method extended-light-map --elm-depth-bits 8 --out out/elm-8
    python3 scripts/side_by_side.py docs/images/elm-fig8c-complex.png 256 \\
        "out/elm-spot/image.png=spot (--elm-pattern 0)" \\
        "out/elm-gobo/image.png=projected texture (1)" "out/elm-8/image.png=8-bit distances"

docs/images/open-meshes.png (shadow-volume on open meshes): the commands in docs/images/open-meshes.toml, then
    python3 scripts/side_by_side.py docs/images/open-meshes.png 320 \\
        "out/open/exact/image.png=reference-hard" \\
        "out/open/sv1/image.png=shadow-volume --sv-open 1" \\
        "out/open/sv0/image.png=shadow-volume --sv-open 0" \\
        "out/open/cmp0/shadow-volume-hard-error.png=--sv-open 0 vs exact (blue: missed)"

The pictures of whole comparisons are compare's own montage.png (`dbuffer compare`)."""

import sys

from PIL import Image, ImageDraw, ImageFont

FONT = ImageFont.truetype("assets/fonts/DejaVuSans.ttf", 14)
CAPTION = 20


def main(out, size, pairs):
    tiles = []
    for pair in pairs:
        path, caption = pair.split("=", 1)
        img = Image.open(path).convert("RGB")
        height = round(img.height * size / img.width)
        tiles.append((img.resize((size, height), Image.LANCZOS), caption))
    height = max(t.height for t, _ in tiles)
    page = Image.new("RGB", (len(tiles) * size, height + CAPTION), (30, 30, 30))
    draw = ImageDraw.Draw(page)
    for i, (tile, caption) in enumerate(tiles):
        page.paste(tile, (i * size, CAPTION))
        draw.text((i * size + 5, 2), caption, fill=(235, 235, 235), font=FONT)
    page.save(out, optimize=True)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3:])
