"""Gas phase: FiPy meshes and the discrete operators of the volume-averaged equations.

FiPy defines the discretization; ``operators`` assembles the same matrices from FiPy's mesh geometry
into cached sparse patterns (tested equal to FiPy's term matrices), so that the hot loop does not
rebuild FiPy terms every step.
"""
