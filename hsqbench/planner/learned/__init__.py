"""Learned grasp detectors run in the same harness as hsq (optional extra ``learned``).

- :mod:`.contact_graspnet`: the ``contact-graspnet`` and ``contact-graspnet-elim`` planners.
- :mod:`.frames`: pure numpy conversions between the harness's and the network's frames.
- :mod:`.network`: the only module that imports torch and cgn-pytorch.

Install: ``pip install -e '.[learned]'`` then ``make learned`` (see the README).
"""
