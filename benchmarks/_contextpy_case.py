"""The B-min case written for contextpy3 (its partials are found by redefining the name)."""

from contextpy3 import Layer, around, base, proceed  # type: ignore[import-not-found]

L = Layer("L")


@base
def bmin(x):  # type: ignore[no-untyped-def]
    return x + 1


@around(L)
def bmin(x):  # type: ignore[no-untyped-def] # noqa: F811 - contextpy3's registration style
    return proceed(x)
