"""Orthogonal cutting: the extended Oxley model, the Kienzle fit, the tool and workpiece geometry.

:mod:`wendel.cutting.oxley` predicts forces, chip thickness and temperatures in milliseconds;
:mod:`wendel.cutting.kienzle` fits ``F_c = b k_c1.1 h^(1 - m_c)`` to rows of F_c(h);
:mod:`wendel.cutting.tool` gives the tool polygon (rake face, rounded edge, flank face);
:mod:`wendel.cutting.chip` turns forces and chip shapes into shear and friction angles, and finds the steady state;
:mod:`wendel.cutting.campaign` runs Oxley over speed, uncut chip thickness and rake and fits Kienzle's law;
:mod:`wendel.cutting.scene` turns a scene's ``[cutting]``, ``[plasticity]`` and ``[thermal]`` tables
into the model's inputs and writes the prediction.
"""
