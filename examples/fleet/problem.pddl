; The depot: each robot waits at its dock; the crates stand in the store; the lab and
; the office are on either side of the store.
(define (problem depot-floor) (:domain depot)
  (:objects
    r1 r2 r3 - robot
    dock1 dock2 dock3 store lab office - place
    parcel1 parcel2 parcel3 - crate)
  (:init
    (at r1 dock1) (at r2 dock2) (at r3 dock3)
    (hands_free r1) (hands_free r2) (hands_free r3)
    (= (battery r1) 100) (= (battery r2) 100) (= (battery r3) 100)
    (road dock1 store) (road store dock1)
    (road dock2 store) (road store dock2)
    (road dock3 store) (road store dock3)
    (road store lab) (road lab store)
    (road store office) (road office store)
    (crate_at parcel1 store) (crate_at parcel2 store) (crate_at parcel3 store))
  (:goal (and)))
