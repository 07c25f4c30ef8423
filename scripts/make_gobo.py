#!/usr/bin/env python3
"""Writes assets/gobo.png, the projected texture (a "gobo") of the `extended-light-map` method's
`--elm-pattern 1`: a four-pane window, each pane tinted, between dark mullions, so the pattern
and the colour of the light are both plain to see on the receivers. Made for this project; no
licence question. Needs Pillow. Run from the repository root: python3 scripts/make_gobo.py"""

from PIL import Image

SIZE = 128
FRAME = 6
MULLION = 5
PANES = {
    (0, 0): (255, 214, 150),  # amber
    (1, 0): (185, 210, 255),  # pale blue
    (0, 1): (255, 185, 185),  # rose
    (1, 1): (200, 255, 200),  # pale green
}


def pixel(x: int, y: int):
    if min(x, y, SIZE - 1 - x, SIZE - 1 - y) < FRAME:
        return (0, 0, 0)
    half = SIZE // 2
    if abs(x - half + 0.5) < MULLION or abs(y - half + 0.5) < MULLION:
        return (0, 0, 0)
    return PANES[(int(x >= half), int(y >= half))]


def main() -> None:
    img = Image.new("RGB", (SIZE, SIZE))
    img.putdata([pixel(x, y) for y in range(SIZE) for x in range(SIZE)])
    img.save("assets/gobo.png", optimize=True)


if __name__ == "__main__":
    main()
