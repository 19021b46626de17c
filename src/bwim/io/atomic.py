"""Atomic output files for the io writers (the primitive is :mod:`bwim.atomic`).

Contract
--------
Every writer of :mod:`bwim.io` writes through :func:`atomic_output` (binary files, by
path) or :func:`atomic_open` (text files): the output appears complete or not at all, and
an unwritable path is an :class:`~bwim.errors.InputError` naming it before any work is
done (:func:`check_writable`).  These are the names of :mod:`bwim.atomic`, re-exported as
the io layer's vocabulary; nothing is reimplemented here.
"""

from bwim.atomic import atomic_open, atomic_output, check_writable

__all__ = ["atomic_open", "atomic_output", "check_writable"]
