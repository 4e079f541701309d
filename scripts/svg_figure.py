"""What the documentation figures share (scripts/plot_training.py, scripts/plot_runs.py): an SVG page with a
white background and a title, written as one file. Standard library only."""


def begin(width, height, title, x, y):
    """The opening lines of a figure: the page, its white background, the title at (x, y)."""
    return [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'font-family="sans-serif" font-size="12">',
            f'<rect width="{width}" height="{height}" fill="white"/>',
            f'<text x="{x}" y="{y}" font-size="14">{title}</text>']


def save(path, lines):
    """Closes the figure and writes it to path."""
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines + ["</svg>"]) + "\n")
