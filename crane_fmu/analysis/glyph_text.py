"""A line of text that changes every frame of an animation (its clock), drawn from glyph images rendered once.

matplotlib lays out and renders every glyph of a text again each time it is drawn: about 4 ms of an animation
frame's 6. :class:`GlyphText` renders each character once per sub-pixel place (on a scratch canvas, by matplotlib
itself) and blends those images onto each frame at the pen positions the characters' advances give (no kerning).
On a plain background the pixels are matplotlib's, bit for bit (tested); over other artists within 2 of 255
levels (Agg rounds its blend its own way).
"""

import math

import numpy as np

_SUBPIXEL = 64  # FreeType places glyphs in 1/64 pixel: a glyph's image depends on its place only within that


class GlyphText:
    """Draws strings onto frames where, and as, ``text`` (a matplotlib ``Text``, left aligned, not rotated) would.

    Parameters
    ----------
    text : matplotlib.text.Text
        Gives the place (its position, vertical alignment and transform: the first line's baseline is where
        a text of one line would have it), the font and the colour.
    renderer : matplotlib's Agg renderer of the canvas the frames come from (drawn once before).
    """

    def __init__(self, text, renderer):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.colors import to_rgb
        from matplotlib.figure import Figure
        from matplotlib.transforms import IdentityTransform

        self.renderer, self.font = renderer, text.get_fontproperties()
        self.height = int(renderer.height)
        shown, text_string = text.get_visible(), text.get_text()
        text.set_text("lp")  # matplotlib's line of one text: at least as high and as deep as "lp"
        box = text.get_window_extent(renderer)
        alignment = text.get_verticalalignment()
        text.set_verticalalignment("baseline")  # the same line with its baseline at the position: how deep it is
        descent = text.get_transform().transform(text.get_position())[1] - text.get_window_extent(renderer).y0
        text.set_verticalalignment(alignment)
        text.set_text(text_string)
        self.x, self.baseline = box.x0, box.y0 + descent
        text.set_visible(shown)
        self.pad = math.ceil(3 * self.font.get_size_in_points() * renderer.dpi / 72)  # room for any glyph
        scratch = Figure(figsize=(4 * self.pad / renderer.dpi, 4 * self.pad / renderer.dpi), dpi=renderer.dpi,
                         facecolor="white")
        self.scratch = FigureCanvasAgg(scratch)
        self.glyph = scratch.text(0, 0, "", transform=IdentityTransform(), fontproperties=self.font, color="black",
                                  va="baseline", ha="left")
        self.scratch.draw()
        self.blank = self.scratch.copy_from_bbox(scratch.bbox)
        self.colour = np.array([round(255 * v) for v in to_rgb(text.get_color())], dtype=np.int32)
        self.advances, self.images = {}, {}

    def advance(self, c):
        """The pen's advance over ``c`` [pixels], from widths matplotlib measures (ten of them, between bars)."""
        if c not in self.advances:
            width = self.renderer.get_text_width_height_descent
            self.advances[c] = (width("|" + c * 10 + "|", self.font, False)[0]
                                - width("||", self.font, False)[0]) / 10
        return self.advances[c]

    def _image(self, c, fraction):
        """``(coverage, row, column)`` of ``c`` with its pen ``fraction``/64 of a pixel right of a whole pixel and the
        baseline's own fraction: its coverage (0-255) and where its top left is, from the pen's whole pixel."""
        key = (c, fraction)
        if key not in self.images:
            self.scratch.restore_region(self.blank)
            self.glyph.set_text(c)
            self.glyph.set_position((self.pad + fraction / _SUBPIXEL, self.pad + self.baseline % 1))
            self.scratch.figure.draw_artist(self.glyph)
            coverage = 255 - np.asarray(self.scratch.buffer_rgba())[..., 0].astype(np.int32)
            rows, columns = np.nonzero(coverage)
            if not len(rows):
                self.images[key] = None
            else:
                r0, c0 = rows.min(), columns.min()
                height = int(self.scratch.renderer.height)
                # the scratch's row r is the frame's row r + (frame height - scratch height) - (baseline's pixel - pad)
                self.images[key] = (coverage[r0:rows.max() + 1, c0:columns.max() + 1, None],
                                    r0 + self.height - height - (math.floor(self.baseline) - self.pad),
                                    c0 - self.pad)
        return self.images[key]

    def draw(self, image, s):
        """Blend ``s`` onto ``image`` (the canvas's RGBA pixels, its first row the top), as Agg blends a glyph."""
        x = self.x
        for c in s:
            pen = math.floor(x * _SUBPIXEL + 0.5) / _SUBPIXEL
            whole = math.floor(pen)
            glyph = self._image(c, round((pen - whole) * _SUBPIXEL))
            x += self.advance(c)
            if glyph is None:
                continue
            coverage, row, column = glyph
            column += whole
            top, left = max(row, 0), max(column, 0)
            bottom, right = min(row + coverage.shape[0], image.shape[0]), min(column + coverage.shape[1],
                                                                                image.shape[1])
            if top >= bottom or left >= right:
                continue
            part = image[top:bottom, left:right, :3].astype(np.int32)
            alpha = coverage[top - row:bottom - row, left - column:right - column]
            image[top:bottom, left:right, :3] = part + ((self.colour - part) * alpha + 127) // 255

