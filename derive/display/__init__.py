"""The model's equations in LaTeX, as derive/ builds them (for the equations notebook).

A chain (derive/chain.py) holds every named quantity of the derivation as components: the
vector ``u_1`` is three symbols defined by three expressions in other components. This package
writes each definition back as one equation between vectors. It knows which symbols are the
components of which vector or matrix (the chain's input blocks and its steps of several
entries) and recognises, in the component expressions, the operations the derivation is made
of; every form it writes equals the components it stands for, term by term:

* sums of vectors times scalars, ``M v`` and ``M^T v`` (M an input matrix, a sum of them, or a
  matrix whose columns are vectors), ``a x b``, ``a . b``, ``|a|``;
* a stacked pair of vectors for the six-entry columns of the 6x6 system (2)-(7);
* what is left, such as the weight along z, along the unit vectors ``e_x``, ``e_y``, ``e_z``.

A definition in which no such form is found is written by components. With ``expand=True``
every vector definition is followed by its components, the way the generated C computes them.

Names follow the paper where it has them: vectors bold (``\\mathbf{u}_{1}``), components with
the axis last (``u_{1,x}``), matrix entries with the body as superscript (``I^{L}_{11}``).
``printed(group)`` gives the paper's printed equations of a group (derive/printed.py and
derive/printed_legs.py, exactly as printed) and ``errata(group)`` the errata that concern it.

The package: names.py (the LaTeX names of symbols, ``legend``), printer.py (the LaTeX printer),
view.py (the vector view, ``equations`` and ``symbol_names``) and paper.py (``printed`` and
``errata``).

Display only: nothing here generates code (derive/sources.py does not hash this package).
"""

from .names import legend
from .paper import GROUP_RANGES, errata, printed
from .view import GROUPS, equations, symbol_names

__all__ = ["GROUPS", "GROUP_RANGES", "equations", "errata", "legend", "printed", "symbol_names"]
