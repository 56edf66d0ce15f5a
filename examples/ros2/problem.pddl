; The world the patrol robot starts in: three places, poses under objects: in robot.yaml.
(define (problem patrol-world) (:domain patrol)
  (:objects dock lab office - place)
  (:init
    (robot_at dock)
    (= (travel_time dock lab) 4) (= (travel_time lab dock) 4)
    (= (travel_time lab office) 3) (= (travel_time office lab) 3)
    (= (travel_time office dock) 5) (= (travel_time dock office) 5))
  (:goal (and)))
