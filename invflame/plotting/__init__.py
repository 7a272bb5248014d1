"""Figures (matplotlib, Agg backend, PNG)."""

from pathlib import Path


def save_figure(fig, path, dpi: int):
    """Write ``fig`` to ``path`` (its folder created) when ``path`` is given; return ``fig``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike or None
        The PNG to write; None writes nothing.
    dpi : int
        Resolution in dots per inch.
    """
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    return fig
