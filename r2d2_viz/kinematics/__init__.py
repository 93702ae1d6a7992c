"""The pinned kinematics core: joint values → joint transforms and link poses, vectorised over samples, and
rigid-transform maths. Pure numpy; imports ``robot`` (the model) and below.
"""
