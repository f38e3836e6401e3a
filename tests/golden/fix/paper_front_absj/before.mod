MODULE PaperFront
    ! The paper's front-cube targets (Table 3/5), tool0, orientation Ry(90),
    ! confdata of the RoboDK configurations (Table 5).
    CONST num NROW := 3;
    CONST robtarget pRow{3}:=[
        [[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[400,150,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[400,0,250],[0.707107,0,0.707107,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    CONST robtarget p4:=[[400,-150,250],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST jointtarget jStart:=[[41.85,44.63,25.88,43.53,-75.61,-13.29],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        VAR num i;
        MoveAbsJ jStart, v100, fine, tool0;
        FOR i FROM 1 TO NROW DO
            MoveL pRow{i}, v100, fine, tool0;
        ENDFOR
        MoveL p4, v100, fine, tool0\WObj:=wobj0;
        MoveL [[400,-300,250],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v100, fine, tool0;
        MoveL Offs(p4, 150, 0, 150), v100, fine, tool0;
        MoveL RelTool(p4, 0, 0, -20), v100, fine, tool0;
        MoveL CRobT(), v100, fine, tool0;
    ENDPROC
ENDMODULE
