; The building, with a goal for `dura plan --offline`: the parcel to the lab, and the
; robot back at its dock.
; The building: a dock and a store on the ground floor, a lab upstairs. The lift
; runs between the ground-floor hall and the first-floor hall and waits upstairs.
(define (problem transport-parcel) (:domain transport)
  (:objects
    dock store hall0 hall1 lab - place
    parcel - crate)
  (:init
    (robot_at dock)
    (hands_free)
    (docking_station dock)
    (road dock store) (road store dock)
    (road dock hall0) (road hall0 dock)
    (road store hall0) (road hall0 store)
    (road hall1 lab) (road lab hall1)
    (lift_stop hall0 hall1) (lift_stop hall1 hall0)
    (lift_at hall1)
    (crate_at parcel store))
  (:goal (and (crate_at parcel lab) (robot_at dock))))
