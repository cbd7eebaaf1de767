"""Checkpoints of an ice body split over MPI ranks: each rank's local state and layout, no gather.

:class:`DistributedCheckpoint` is mixed into :class:`pdfem.pd.layout.halo.DistributedIce`. A
checkpoint stores each rank's owned particles and counted bonds under their global numbers
(:mod:`pdfem.pd.checkpoint.parts`; written by :mod:`pdfem.run.checkpoint`), and a restart on any
number of ranks gives each rank the state of its local particles and bonds from those parts.
Nothing here is collective except the restore's halo refresh. SI units as the serial body's
(:mod:`pdfem.pd.checkpoint.state`).
"""

from __future__ import annotations

from pdfem.pd.checkpoint.parts import Layout


class DistributedCheckpoint:
    """``checkpoint_state`` / ``restore_state`` / ``checkpoint_layout`` of a distributed body."""

    def checkpoint_state(self) -> dict:
        """The state of this rank's local (owned and halo) particles and bonds, as the serial
        body's :meth:`~pdfem.pd.body.IceBody.checkpoint_state` of the local body; its
        ``external_work`` and ``fracture_dissipated`` are this rank's parts (J)."""
        return self.body.checkpoint_state()

    def checkpoint_layout(self) -> Layout:
        """Global numbers of the local particles, which are owned, which bonds this rank counts
        (the owned particles' rows) and the local bond list. Particles may move between ranks
        during a run: this is the layout now."""
        b = self.body
        return Layout(self.plan.local, self.plan.owned, self._counted, b.row_ptr, b.nbr,
                      int(self.global_n))

    def restore_state(self, state: dict) -> None:
        """Take the state of this rank's local particles and bonds (in
        :meth:`checkpoint_layout` order; from :class:`pdfem.pd.checkpoint.parts.PartPicker`)
        and refresh the counters and the halo's weighted volumes (collective).

        Raises
        ------
        ValueError
            If the state's sizes are not those of the local body.
        """
        self.body.restore_state(state)
        self._counted_broken = self._broken_count()
        self.update_intact_volume()  # the halo's from their owners
