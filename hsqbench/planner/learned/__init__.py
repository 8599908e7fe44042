"""Learned grasp detectors run in the same harness as hsq (optional extra ``learned``).

- :mod:`.contact_graspnet`: the ``contact-graspnet`` and ``contact-graspnet-elim`` planners.
- :mod:`.frames`: pure numpy conversions between the harness's and the network's frames.
- :mod:`.network`: the only module that imports torch and cgn-pytorch.
- :mod:`.volumetric`: the ``vgn`` and ``giga`` planners (torch alone), with :mod:`.tsdf`,
  :mod:`.vgn_net`, :mod:`.giga_net`, :mod:`.detection`, :mod:`.weights` and
  :mod:`.volumetric_config`; see docs/learned-baselines.md.

Install: ``pip install -e '.[learned]'`` then ``make learned`` (see the README).
"""
